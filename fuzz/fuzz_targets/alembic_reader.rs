//! Feeds arbitrary bytes to the Alembic reader: it must return a groom or an error, never
//! panic, hang or allocate beyond what the input justifies.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.abc");
    let _ = coif::io::alembic::read(data, path, None, false);
    let _ = coif::io::alembic::read(data, path, Some(2.0), false);
    let _ = coif::io::alembic::read_all_frames(data, path, false);
});
