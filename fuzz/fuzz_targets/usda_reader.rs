//! Feeds arbitrary bytes to the `.usda` reader, with and without a time: a groom, a request
//! for composition or an error, never a panic or a stack overflow at any nesting.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.usda");
    let options = coif::io::ImportOptions::default();
    let _ = coif::io::usda::read(data, path, &options, None);
    let _ = coif::io::usda::read(data, path, &options, Some(1.5));
});
