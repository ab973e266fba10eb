//! The bench-scenario parser on arbitrary text.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = illume_bench::Scenario::parse(text, std::path::Path::new("fuzz.toml"));
    }
});
