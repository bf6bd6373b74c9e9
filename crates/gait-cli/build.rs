//! Python stages run in an interpreter embedded in `gait`: the binary finds
//! the libpython it was linked against (e.g. pyenv's) before the system's.

fn main() {
    let config = pyo3_build_config::get();
    if let Some(dir) = config.lib_dir() {
        println!("cargo:rustc-link-arg-bins=-Wl,-rpath,{dir}");
    }
}
