//! Points the linker at the Embree 4 library that `make setup` unpacks into `.deps/embree`
//! (from the `embreex` wheel: Debian 12 only packages Embree 3). `embree4-sys` itself asks for
//! `-lembree4`; we add the search path and an rpath so binaries and tests run without
//! LD_LIBRARY_PATH. `COIF_EMBREE_DIR` overrides the location.
use std::path::PathBuf;

fn main() {
    println!("cargo:rerun-if-env-changed=COIF_EMBREE_DIR");
    let dir = match std::env::var_os("COIF_EMBREE_DIR") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap()).join(".deps/embree"),
    };
    if !dir.join("libembree4.so").exists() {
        println!("cargo:warning=Embree 4 not found in {}; run `make setup` first", dir.display());
    }
    println!("cargo:rustc-link-search=native={}", dir.display());
    println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    println!("cargo:rerun-if-changed={}", dir.join("libembree4.so").display());
}
