//! Feeds arbitrary bytes to the crate-file (`.usdc`) reader: it must return a groom, an error
//! or "needs composition", never panic, hang or allocate beyond what the input justifies.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.usdc");
    let options = Default::default();
    for time in [None, Some(1.5)] {
        let _ = coif::io::usdc::read(data, path, &options, time);
    }
});
