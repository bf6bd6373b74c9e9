"""The people the subject pass found in every frame of a run, as one JSON fixture.

    python3 tools/subject/sightings_fixture.py RUN_DIR OUT.json

RUN_DIR is a `gait run` folder of a video (e.g. a variant of tools/robustness/matrix.py); its
cache/subject-*/ holds the detector's people per frame (BlazePose's detector, which
crates/gait-pose's fixtures prove equal to mediapipe's). The fixture is `[[frame, [sighting, ...]],
...]`, read by crates/gait-subject/tests/real_sightings.rs.
"""
import glob
import json
import pathlib
import sys


def main():
    run, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    [cache] = glob.glob(str(run / "cache" / "subject-*"))
    frames = []
    for path in sorted(pathlib.Path(cache).glob("[0-9]*.json")):
        # A cache entry is the JSON line, then its checksum line.
        seen = json.loads(path.read_text().split("\n")[0])
        for s in seen:
            # Five digits are a thousandth of a pixel: plenty, and a small file.
            s["person"] = {k: [round(x, 3) for x in v] if isinstance(v, list) else round(v, 5)
                           for k, v in s["person"].items()}
            s["appearance"] = [None if x is None else round(x, 5) for x in s["appearance"]]
        frames.append([int(path.stem), seen])
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(frames, separators=(",", ":")) + "\n")
    print(f"{out}: {len(frames)} frames, {sum(len(s) for _, s in frames)} sightings")


if __name__ == "__main__":
    main()
