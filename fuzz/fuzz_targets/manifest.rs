//! Feeds arbitrary text to the job manifest parser (tasks, wedges, templates): a manifest or an
//! error, never a panic, and never a task whose name or outputs leave its folder.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(manifest) = coif::batch::manifest::parse(text, std::path::Path::new("/m/fuzz.toml")) {
        for task in &manifest.tasks {
            assert!(!task.name.contains('/') && task.name != "..", "{:?}", task.name);
            for output in task.outputs.iter().chain(task.preview.iter()) {
                assert!(!output.components().any(|c| c == std::path::Component::ParentDir), "{output:?}");
            }
        }
    }
});
