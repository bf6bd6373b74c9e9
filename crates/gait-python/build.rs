//! This crate's examples embed Python: they find the libpython they
//! were linked against (e.g. pyenv's) before the system's.

fn main() {
    if let Some(dir) = pyo3_build_config::get().lib_dir() {
        println!("cargo:rustc-link-arg-examples=-Wl,-rpath,{dir}");
    }
}
