//! Feeds arbitrary bytes to the OBJ reader, then bakes the mesh's distance field: an error or a
//! field, never a panic. The bake's cost grows with the triangles times the cells each covers
//! (bounded by `mesh_sdf::MAX_BAKE_VISITS`, minutes at worst): so that an execution stays fast
//! enough for 10^7 of them (at 32 cells across the bake held the target under 1,000 executions a
//! second), meshes are baked on a grid of about 8 cells across, plus the band, and only when they
//! have at most 64 triangles; the reader itself sees every input.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.obj");
    if let Ok((vertices, triangles)) = coif::io::obj::parse_triangles(data, path) {
        if triangles.len() > 64 {
            return;
        }
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        for x in vertices.iter().flat_map(|v| v.to_array()) {
            (lo, hi) = (lo.min(x), hi.max(x));
        }
        let cell = ((hi - lo) / 8.0).max(0.05);
        let _ = coif::interact::mesh_sdf::MeshSdf::bake(&vertices, &triangles, cell, 2.0 * cell);
    }
});
