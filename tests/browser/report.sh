#!/usr/bin/env bash
# `nimbus compare --html` in a real browser:
#
#   NIMBUS=target/release/nimbus bash tests/browser/report.sh
#
# Installs Debian's Chromium if missing, renders a reference of a tiny shipped scene (64×48)
# in two halves
# into a scratch folder (so nothing is cached next to the scene in the repository), compares two
# integrators against it with --html, and loads the page in headless Chromium. The page checks
# itself on load (a view per image, no script errors, number keys switch the flip view, a path
# per chart series) and writes its verdict to <body data-selfcheck>. Fails unless the dumped DOM
# says data-selfcheck="pass" and Chromium logged no console error or uncaught exception from the
# page. About 10 s once Chromium is installed.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/../.." && pwd)
NIMBUS=${NIMBUS:-$ROOT/target/debug/nimbus}
SCENE=$ROOT/pbrt-scenes/pbrt-v4-parity/shapes.pbrt
WORK=$(mktemp -d /tmp/nimbus-browser.XXXXXX)
trap 'rm -rf "$WORK"' EXIT

say() { echo "browser test: $*"; }
fail() { echo "browser test: FAILED: $*" >&2; exit 1; }

[ -x "$NIMBUS" ] || fail "no nimbus binary at $NIMBUS (build it, or set NIMBUS)"

if ! command -v chromium >/dev/null; then
    say "installing Debian's chromium"
    SUDO=()
    if [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null; then SUDO=(sudo); fi
    "${SUDO[@]}" apt-get update -q >/dev/null
    "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null
fi
command -v chromium >/dev/null || fail "chromium is not installed"

say "rendering the reference and comparing volpath, simplevolpath on $(basename "$SCENE")"
# The reference as two independent halves, two seeds per method: the page shows the first
# seed's images and every seed's curve.
"$NIMBUS" render "$SCENE" --spp 8 --seed 98 --outfile "$WORK/ref-a.exr" --quiet
"$NIMBUS" render "$SCENE" --spp 8 --seed 99 --outfile "$WORK/ref-b.exr" --quiet
"$NIMBUS" compare "$SCENE" --integrators volpath,simplevolpath --spp 4 --seeds 2 --seed 1 \
    --reference "$WORK/ref-a.exr,$WORK/ref-b.exr" \
    --out "$WORK/out" --html "$WORK/out/report.html" --quiet >"$WORK/compare.log"
PAGE=$WORK/out/report.html
[ -s "$PAGE" ] || fail "compare wrote no $PAGE"
say "page: $(wc -c <"$PAGE") bytes"
if grep -Eiq '(src|href)=["'"'"']?(https?:)?//|https?://' "$PAGE"; then
    fail "the page refers to a network address"
fi

# Its own profile and a scratch HOME, so no state of an earlier run (or of the user) is read.
set +e
HOME=$WORK/home timeout 120 chromium --headless --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$WORK/profile" --enable-logging=stderr --v=0 --virtual-time-budget=5000 \
    --dump-dom "file://$PAGE" >"$WORK/dom.html" 2>"$WORK/chromium.log"
status=$?
set -e
[ "$status" -eq 0 ] || { tail -n 20 "$WORK/chromium.log" >&2; fail "chromium exited with $status"; }

# Console messages of the page: Chromium logs them as "...:CONSOLE(line)] "message", source:
# file:///... (line)" (or "CONSOLE: ..." in newer builds). Errors are uncaught exceptions and
# console.error calls; dbus, GPU and other noise of Chromium itself is not from the page.
console=$(grep -E 'CONSOLE' "$WORK/chromium.log" || true)
errors=$(printf '%s\n' "$console" | grep -Ei 'ERROR:CONSOLE|Uncaught|error' || true)
verdict=$(grep -o 'data-selfcheck="[^"]*"' "$WORK/dom.html" | head -n 1 || true)

if [ -n "$console" ]; then
    say "the page's console:"
    printf '%s\n' "$console" | sed 's/^/    /'
fi
if [ -n "$errors" ]; then
    fail "the page logged errors in Chromium's console (above)"
fi
case "$verdict" in
    'data-selfcheck="pass"')
        say "PASSED: the page's self-check passed in headless Chromium ($(chromium --version 2>/dev/null || echo chromium))"
        ;;
    '')
        fail "the dumped DOM has no data-selfcheck on <body> (the page's script did not finish)"
        ;;
    *)
        fail "the page's self-check says ${verdict#data-selfcheck=}"
        ;;
esac
