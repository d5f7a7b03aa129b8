//! Feeds arbitrary text to the recipe parser and, when it parses, to what `style` does with a
//! recipe before simulating: estimating its memory and steps (`limits::check_style`), then
//! placing it on a groom (the head frame). An error naming the line or the figure, never a panic, an
//! abort or an allocation. (Mesh obstacles name files that do not exist here: an error.)
#![no_main]
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

/// A small generated head: enough for the head frame's fit, cheap to place on.
fn groom() -> &'static coif::Groom {
    static GROOM: OnceLock<coif::Groom> = OnceLock::new();
    GROOM.get_or_init(|| {
        let params = coif::generate::GenerateParams { strands: 24, vertices_per_strand: 6, ..Default::default() };
        coif::generate::generate(&params).expect("the default head generates")
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(recipe) = coif::style::recipe::parse(text, std::path::Path::new("/nonexistent/fuzz.toml")) else {
        return;
    };
    // In the order `style::style` takes them: the limits first, then the head frame fitted to
    // the whole groom, then the placement in it.
    if coif::limits::check_style(groom(), &recipe, 24.0).is_ok() {
        if let Ok(frame) = coif::style::placement::head_frame(&recipe, groom(), None) {
            let _ = coif::style::placement::place(&recipe, groom(), None, frame);
        }
    }
});
