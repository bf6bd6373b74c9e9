//! Fetches the BlazePose models (what `gait models fetch blazepose` does):
//! `cargo run -p gait-pose --example blazepose_fetch -- MODELS_DIR`.

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "models".into());
    match gait_pose::blazepose::fetch::fetch(std::path::Path::new(&dir)) {
        Ok(files) => {
            for f in files {
                println!("{}", f.display());
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
