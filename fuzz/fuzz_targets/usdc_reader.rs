//! Feeds arbitrary bytes to the crate-file (`.usdc`) reader, and composes what needs
//! composition: a groom or an error, never a panic, a hang or an allocation beyond what the
//! input justifies.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.usdc");
    let options = Default::default();
    for time in [None, Some(1.5)] {
        if let Ok(coif::io::usdc::ReadOutcome::NeedsComposition(layer)) =
            coif::io::usdc::read(data, path, &options, time)
        {
            let selection = coif::io::usda::Selection { time, variants: vec![] };
            let _ = coif::io::usd_compose::groom_from_composed(*layer, path, &options, &selection);
        }
    }
});
