//! Feeds arbitrary bytes to the parser and the scene builder. Nothing may panic; and whatever
//! parses into directives must print and parse back to the same directives.
#![no_main]

use libfuzzer_sys::fuzz_target;
use nimbus_parser::{SceneBuilder, directives_of_str, parse_bytes, to_pbrt};

fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

fuzz_target!(|data: &[u8]| {
    // The scene builder follows Include and Import, which read the files the input names: an
    // input naming /dev/zero or /dev/stdin would hang the fuzzer. Such inputs go only through
    // the directive parser below, which does not follow files.
    if !contains(data, b"Include") && !contains(data, b"Import") {
        let mut builder = SceneBuilder::new();
        if parse_bytes(data, "fuzz.pbrt", &mut builder).is_ok() {
            let _ = builder.finish();
        }
    }
    if let Ok(text) = std::str::from_utf8(data)
        && let Ok(directives) = directives_of_str(text, "fuzz.pbrt")
    {
        let printed = to_pbrt(&directives);
        match directives_of_str(&printed, "printed.pbrt") {
            Ok(again) => assert_eq!(again, directives, "printed:\n{printed}"),
            Err(e) => panic!("printed directives do not parse: {e}\nprinted:\n{printed}"),
        }
    }
});
