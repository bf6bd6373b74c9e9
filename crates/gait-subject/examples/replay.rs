//! Replays the subject pass's linking on a run's cached sightings and prints
//! each track's frames: `cargo run -p gait-subject --example replay -- RUN/cache/subject-*`.

use gait_core::{PersonChoice, ranges};
use gait_subject::{Sighting, SubjectConfig, find};

fn main() {
    let dir = std::env::args()
        .nth(1)
        .expect("usage: replay CACHE_DIR [FPS]");
    let fps: f64 = std::env::args()
        .nth(2)
        .map_or(30.0, |f| f.parse().expect("fps"));
    let mut frames: Vec<(usize, Vec<Sighting>)> = Vec::new();
    for f in 0.. {
        let path = format!("{dir}/{f:06}.json");
        let Ok(text) = std::fs::read_to_string(&path) else {
            break;
        };
        let json = text.lines().next().unwrap_or("[]");
        let seen = serde_json::from_str(json).unwrap_or_else(|e| panic!("{path}: {e}"));
        frames.push((f, seen));
    }
    let limits = gait_subject::LinkLimits {
        max_gap_frames: (2.0 * fps) as usize,
        max_size_ratio: 1.4,
        max_colour_distance: 0.1,
        short_gap_frames: (0.2 * fps).round() as usize,
    };
    for (i, t) in gait_subject::link::link(&frames, &limits)
        .iter()
        .enumerate()
    {
        println!(
            "linked {i} {:?}",
            ranges(t.sightings.iter().map(|x| x.frame))
        );
    }
    let s = find(
        &frames,
        PersonChoice::default(),
        &SubjectConfig::default(),
        fps,
        (1920, 1080),
    )
    .expect("subject");
    for t in &s.tracks {
        let mark = if t.id == s.chosen { "*" } else { " " };
        println!(
            "{mark}{} {:?}",
            t.id,
            ranges(t.sightings.iter().map(|x| x.frame))
        );
    }
    println!("{}", s.reason);
    if std::env::var_os("REPLAY_BOXES").is_some() {
        for (f, b) in &s.boxes {
            println!("box {f} {:.1}", b.centre[0]);
        }
    }
}
