//! Files that declare huge sizes are refused before anything that size is allocated. This test
//! binary has the fuzzer's allocation limit (1 GiB per allocation): a parser that believed the
//! declared size would abort it.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write as _;

struct Limited;

// SAFETY: forwards to the system allocator; requests over the limit abort before allocating.
unsafe impl GlobalAlloc for Limited {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        check(layout.size());
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        check(new_size);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

fn check(size: usize) {
    if size > 1 << 30 {
        let _ = std::io::stderr().write_all(b"allocation over the 1 GiB limit\n");
        std::process::abort();
    }
}

#[global_allocator]
static ALLOC: Limited = Limited;

fn repo() -> std::path::PathBuf {
    gait_fuzz::repo()
}

#[test]
fn a_safetensors_header_declaring_a_trillion_elements() {
    let header = br#"{"w":{"dtype":"F32","shape":[1000000,1000000],"data_offsets":[0,16]}}"#;
    let mut file = (header.len() as u64).to_le_bytes().to_vec();
    file.extend_from_slice(header);
    file.extend_from_slice(&[0u8; 16]);
    assert!(candle_core::safetensors::load_buffer(&file, &candle_core::Device::Cpu).is_err());
}

#[test]
fn checkpoints_declaring_gigabytes() {
    let dir = tempfile::tempdir().unwrap();
    for case in ["legacy_huge_string", "zip_huge_string"] {
        let bytes = std::fs::read(repo().join(format!("fuzz/regressions/pth/{case}.bin"))).unwrap();
        let p = dir.path().join("model.pth");
        std::fs::write(&p, bytes).unwrap();
        let e = gait_pose::openpose::net::read_checkpoint(&p)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("declares") && e.contains("bytes but only"),
            "{case}: {e}"
        );
    }
}

#[test]
fn a_toml_nested_a_hundred_thousand_deep() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("deep.toml");
    let deep = format!(
        "[run]\nbatch_size = {}{}\n",
        "[".repeat(100_000),
        "]".repeat(100_000)
    );
    std::fs::write(&p, deep).unwrap();
    assert!(gait_pipeline::PipelineConfig::load(Some(&p), &[]).is_err());
    let c = dir.path().join("corrections.toml");
    std::fs::write(
        &c,
        format!("swap = {}1{}\n", "[".repeat(100_000), "]".repeat(100_000)),
    )
    .unwrap();
    let e = gait_kin::Corrections::read(&c).unwrap_err().to_string();
    assert!(e.contains("recursion"), "{e}");
}

#[test]
fn a_keypoints_file_with_a_frame_number_near_2_to_the_64() {
    let seed =
        std::fs::read_to_string(repo().join("fuzz/seeds/dlc_csv/walk_frames_100_129.csv")).unwrap();
    let mut lines: Vec<String> = seed.lines().map(String::from).collect();
    let last = lines.len() - 1;
    let rest = lines[last].split_once(',').unwrap().1.to_string();
    lines[last] = format!("18446744073709551000,{rest}");
    let seq = gait_core::dlc::read(lines.join("\n").as_bytes(), None, 30.0).unwrap();
    let e = gait_kin::analyse(&seq, &Default::default(), &Default::default()).unwrap_err();
    assert!(e.to_string().contains("beyond 1000000000"), "{e}");
}

#[test]
fn a_csv_with_a_million_columns_costs_what_its_bytes_cost() {
    // A header cannot declare columns it does not have: a million-column file is read in
    // proportion to its 7 MB, and refused for its layout.
    let mut csv = String::from("scorer");
    for k in 0..1_000_000 {
        csv.push_str(&format!(",k{k}"));
    }
    csv.push('\n');
    assert!(gait_core::dlc::read(csv.as_bytes(), None, 30.0).is_err());
}
