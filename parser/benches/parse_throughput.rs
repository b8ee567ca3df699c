//! Parse throughput on a generated scene: a 1M-triangle `trianglemesh` and a 100k-value
//! `uniformgrid`, the bulk of real pbrt-v4 scenes. Run with `cargo bench -p nimbus-parser`.
//! Reports MB/s on one core (the parser is single-threaded), best of several runs.

use std::fmt::Write;
use std::time::Instant;

fn generated_scene() -> String {
    // A jittered 708x708 vertex grid gives just over 1M triangles.
    let n = 708usize;
    let mut s = String::new();
    s.push_str("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\nWorldBegin\n");
    s.push_str("Shape \"trianglemesh\"\n  \"point3 P\" [\n");
    let mut state = 0x2545f4914f6cdd1du64;
    let mut rnd = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    for j in 0..n {
        for i in 0..n {
            let x = i as f32 / n as f32 * 2.0 - 1.0;
            let y = j as f32 / n as f32 * 2.0 - 1.0;
            let _ = writeln!(s, "    {x:.6} {y:.6} {:.6}", rnd() * 0.1);
        }
    }
    s.push_str("  ]\n  \"integer indices\" [\n");
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            let _ = writeln!(s, "    {} {} {} {} {} {}", a, a + 1, a + n + 1, a, a + n + 1, a + n);
        }
    }
    s.push_str("  ]\n");
    s.push_str("MakeNamedMedium \"smoke\" \"string type\" \"uniformgrid\" \"integer nx\" 50 \"integer ny\" 50 \"integer nz\" 40\n  \"float density\" [\n");
    for k in 0..100_000 {
        let _ = write!(s, " {:.4}", rnd());
        if k % 16 == 15 {
            s.push('\n');
        }
    }
    s.push_str(" ]\n");
    s
}

fn main() {
    let text = generated_scene();
    let mb = text.len() as f64 / 1e6;
    let mut best = f64::INFINITY;
    let mut triangles = 0;
    for _ in 0..5 {
        let t = Instant::now();
        let scene = nimbus_parser::load_str(&text, "generated.pbrt").expect("generated scene parses");
        let dt = t.elapsed().as_secs_f64();
        triangles = scene.shapes[0].entity.params.get_ints("indices").unwrap().len() / 3;
        best = best.min(dt);
    }
    // Baseline in the same run: the time just to scan every byte for whitespace, the floor any
    // tokenizer pays.
    let t = Instant::now();
    let ws = text.bytes().filter(|b| b.is_ascii_whitespace()).count();
    let scan = t.elapsed().as_secs_f64();
    println!(
        "parse: {mb:.1} MB ({triangles} triangles, 100000 grid values) in {:.3} s = {:.0} MB/s (best of 5); \
         byte scan baseline {:.0} MB/s ({ws} whitespace); parse/scan = {:.2}",
        best,
        mb / best,
        mb / scan,
        scan / best
    );
}
