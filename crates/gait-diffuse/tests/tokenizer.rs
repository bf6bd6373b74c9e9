//! The CLIP tokenizer on the real vocabulary against transformers' CLIPTokenizer
//! (ids in tests/fixtures/tokenizer_cases.json from tools/diffuse/make_fixtures.py).

mod common;

use gait_diffuse::ClipTokenizer;

#[test]
fn token_ids_match_clip_tokenizer() {
    let tok =
        ClipTokenizer::from_merges_file(&common::tiny().join("tokenizer/merges.txt")).unwrap();
    let text = std::fs::read_to_string(common::fixtures().join("tokenizer_cases.json")).unwrap();
    let cases: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    assert!(cases.len() >= 5);
    for case in cases {
        let s = case["text"].as_str().unwrap();
        let want: Vec<u32> = case["ids"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as u32)
            .collect();
        assert_eq!(tok.encode(s), want, "{s:?}");
    }
}
