//! Feeds arbitrary text to the recipe parser and checks: a recipe or an error naming the line,
//! never a panic. (Mesh obstacles name files that do not exist here: an error.)
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = coif::style::recipe::parse(text, std::path::Path::new("/nonexistent/fuzz.toml"));
    }
});
