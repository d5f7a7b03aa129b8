//! Feeds arbitrary bytes to the `.usda` reader, with and without a time, and composes what
//! needs composition (internal references, inherits, variants: the arcs one file can hold): a
//! groom or an error, never a panic, a hang or a stack overflow at any nesting.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.usda");
    let options = coif::io::ImportOptions::default();
    for time in [None, Some(1.5)] {
        if let Ok(coif::io::usda::ReadOutcome::NeedsComposition(layer)) =
            coif::io::usda::read(data, path, &options, time)
        {
            let selection = coif::io::usda::Selection { time, variants: vec![] };
            let _ = coif::io::usd_compose::groom_from_composed(*layer, path, &options, &selection);
        }
    }
});
