//! Helpers shared by the integration tests: run the `coif` binary and inspect what it did.
#![allow(dead_code)]
use std::path::Path;
use std::process::{Command, Output};

pub fn coif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coif")).args(args).output().expect("the coif binary runs")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn stdout_json(output: &Output) -> serde_json::Value {
    assert!(output.status.success(), "coif failed: {}", stderr(output));
    serde_json::from_slice(&output.stdout).expect("stdout is one JSON object")
}

pub fn path_str(path: &Path) -> &str {
    path.to_str().expect("test paths are UTF-8")
}

/// Files in a directory, sorted, to check that nothing (not even a temporary) was left behind.
pub fn dir_listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Every `step`-th strand of a groom, with its widths and attributes: a preset's recipe on a few
/// strands, so a test stays fast while still going through every stage.
pub fn thin(groom: &coif::Groom, step: usize) -> coif::Groom {
    let strands: Vec<usize> = (0..groom.strand_count()).step_by(step).collect();
    coif::groups::assemble(&[(groom, &strands)]).expect("a selection of a valid groom is valid")
}

/// The one PolyMesh of an Alembic file as ogawa-rs (an independent reader) sees it: points,
/// face counts and face indices.
pub fn polymesh_via_ogawa_rs(path: &Path) -> (Vec<[f32; 3]>, Vec<i32>, Vec<i32>) {
    use ogawa_rs::{Archive, FileReader, Schema};
    let mut reader = FileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let archive = Archive::new(&mut reader).unwrap();
    let mut stack = vec![archive.load_root_object(&mut reader).unwrap()];
    while let Some(object) = stack.pop() {
        if let Ok(Schema::PolyMesh(mesh)) = Schema::parse(&object, &mut reader, &archive) {
            return (
                mesh.load_vertices_sample(0, &mut reader).unwrap(),
                mesh.load_facecounts_sample(0, &mut reader).unwrap(),
                mesh.load_faceindices_sample(0, &mut reader).unwrap(),
            );
        }
        for i in 0..object.child_count() {
            stack.push(
                object
                    .load_child(i, &mut reader, &archive.indexed_meta_data, &archive.time_samplings)
                    .unwrap(),
            );
        }
    }
    panic!("{}: ogawa-rs finds no PolyMesh", path.display());
}

pub mod usd;
