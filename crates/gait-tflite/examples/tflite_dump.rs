//! Prints the operators of a `.tflite` file: `cargo run -p gait-tflite --example tflite_dump -- FILE`.

use gait_tflite::Graph;

fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: tflite_dump FILE.tflite");
        std::process::exit(2);
    };
    let g = match Graph::load(std::path::Path::new(&path)) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    for i in &g.inputs {
        println!("input {} {:?}", g.tensors[*i].name, g.tensors[*i].shape);
    }
    for o in &g.outputs {
        println!("output {} {:?}", g.tensors[*o].name, g.tensors[*o].shape);
    }
    for (k, op) in g.operators.iter().enumerate() {
        let shapes: Vec<_> = op
            .inputs
            .iter()
            .map(|&i| {
                if i < 0 {
                    vec![]
                } else {
                    g.tensors[i as usize].shape.clone()
                }
            })
            .collect();
        let out = &g.tensors[op.outputs[0] as usize];
        println!(
            "{k} {:?} {:?} -> {:?} {:?}",
            op.op, shapes, out.shape, op.options
        );
    }
}
