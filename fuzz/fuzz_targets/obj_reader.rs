//! Feeds arbitrary bytes to the OBJ mesh reader and bakes what it accepts into a coarse
//! distance field: an error or a mesh, never a panic or an unbounded grid.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.obj");
    if let Ok((vertices, triangles)) = coif::io::obj::parse_triangles(data, path) {
        let _ = coif::interact::mesh_sdf::MeshSdf::bake(&vertices, &triangles, 0.05, 0.1);
    }
});
