//! Feeds arbitrary bytes to the `.hair` reader: a groom or an error, never a panic or an
//! allocation beyond what the file's length justifies.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = coif::io::hair::read(data, std::path::Path::new("fuzz.hair"));
});
