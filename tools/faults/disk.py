"""A full disk (a small tmpfs as the run folder, filled at different points of the run: the
caches, the CSVs, the overlay video, the PDF), and corrupt cache entries planted in a finished
run. Needs root (mount)."""
import json
import os
import re
import shutil
import subprocess

import runs


def _allocated(path):
    """Bytes a tmpfs charges for a file (whole pages)."""
    return -(-path.stat().st_size // 4096) * 4096


def _sizes(ref):
    """tmpfs sizes that fill up during the subject cache, the regeneration cache, the CSVs,
    the overlay video and the PDF of a run like `ref`."""
    cache = ref / "cache"

    def stage(name):
        return sum(_allocated(f) for f in runs.entries(cache) if f.parent.name.startswith(name + "-"))

    files = {p.name: _allocated(p) for p in ref.iterdir() if p.is_file()}
    subject, edge, regen, pose = (stage(s) for s in ["subject", "edge", "regenerator", "pose"])
    caches = subject + edge + regen + pose
    csvs = sum(v for k, v in files.items() if k.endswith(".csv"))
    exports = sum(files.get(k, 0) for k in ["run.json", "keypoints.c3d", "keypoints.trc", "angles.mot"])
    before_overlay = caches + csvs + exports
    return [
        ("subject cache", subject // 2),
        ("regeneration cache", subject + edge // 2 + regen // 2),
        ("CSVs", caches + csvs // 2),
        ("overlay video", before_overlay + files["overlay.mp4"] // 2),
        ("PDF", sum(files.values()) + caches - files["report.pdf"] // 2),
    ]


def _mount(path, size):
    path.mkdir(parents=True, exist_ok=True)
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)], check=True)


def full_disk(gait, ref, work, log):
    rows = []
    for i, (aim, size) in enumerate(_sizes(ref)):
        disk = work / f"full{i}"
        _mount(disk, max(size, 64 * 1024))
        try:
            out = disk / "run"
            code, err = gait.run(out)
            lines = [l for l in err.splitlines() if l.startswith("error:")]
            row = {"aim": aim, "size": size, "exit": code, "error": lines[-1] if lines else err[-300:]}
            row["one_line"] = len(lines) == 1 and str(disk) in lines[0] and "free space" in lines[0]
            row["partial"] = runs.partial_files(ref, out)
            row["leftovers"] = sorted(p.name for p in out.iterdir() if p.name.endswith(".partial")) if out.is_dir() else []
            row["bad_entries"] = runs.bad_entries(out / "cache")
            subprocess.run(["mount", "-o", "remount,size=2g", str(disk)], check=True)
            code2, err2 = gait.run(out)
            row["resumed"] = code2 == 0
            row["differences"] = runs.differences(ref, out) if code2 == 0 else [err2.strip()[-300:]]
        finally:
            subprocess.run(["umount", str(disk)], check=False)
        row["ok"] = (
            row["exit"] == 1
            and row["one_line"]
            and not row["partial"]
            and not row["leftovers"]
            and not row["bad_entries"]
            and row["resumed"]
            and not row["differences"]
        )
        log(f"full disk {i + 1}/5 ({aim}, {size // 1024} KiB): exit {row['exit']}, "
            f"{row['error'][:160]} -> {'ok' if row['ok'] else 'FAILED ' + json.dumps(row)}")
        rows.append(row)
    return rows


def _plant(path, how):
    data = bytearray(path.read_bytes())
    if how == "truncate":
        data = data[: len(data) // 2]
    elif how == "flip":
        data[len(data) // 3] ^= 0x5A
    else:
        data = bytearray()
    path.write_bytes(bytes(data))


# What a rerun reads, and so must find corrupt and recompute: a frame's pose; its pose and its
# redrawn image; those and its edge map; the people found in it (the subject pass); the tracker's
# state after the frame before it with its pose. (An entry no rerun needs is never read: the
# redrawn image of a frame whose pose is whole, for one.)
PLANS = [
    [("pose", 0, "json")],
    [("pose", 0, "json"), ("regenerator", 0, "png")],
    [("pose", 0, "json"), ("regenerator", 0, "png"), ("edge", 0, "png")],
    [("subject", 0, "json")],
    [("pose", -1, "state"), ("pose", 0, "json")],
]


def _entry(cache, stage, frame, ext):
    found = [d / f"{frame:06d}.{ext}" for d in cache.iterdir() if d.name.startswith(stage + "-")]
    return found[0] if found and found[0].exists() else None


def corruptions(gait, ref, work, n, rng, log):
    """`n` corrupt entries (truncated, a flipped byte, emptied), planted per PLANS in copies of
    the undisturbed run, a few frames a round, each round rerun: every one must be reported and
    recomputed, and the results must be the undisturbed run's."""
    rows = []
    ways = ["truncate", "flip", "empty"]
    first = int(gait.sets[0].split("=")[1])
    planted_total, r = 0, 0
    while planted_total < n:
        out = work / f"corrupt{r}"
        shutil.copytree(ref, out)
        cache = out / "cache"
        frames = rng.sample(range(first + 1, first + gait.frames), 4)
        picked, touched = [], set()
        for k, f in enumerate(frames):
            plan = PLANS[(4 * r + k) % len(PLANS)]
            paths = [_entry(cache, st, f + d, ext) for st, d, ext in plan]
            # Plans on neighbouring frames would overlap: a frame recomputed for one plan
            # rewrites the state another plan corrupted before it is read.
            near = {f + d for _, d, _ in plan} | {f + 1}
            if None in paths or near & touched or planted_total + len(picked) + len(paths) > n:
                continue
            touched |= near
            picked += paths
        for k, f in enumerate(picked):
            _plant(f, ways[(planted_total + k) % 3])
        planted_total += len(picked)
        code, err = gait.run(out)
        warned = set(re.findall(r"cache entry (\S+) failed its checksum", err))
        row = {
            "planted": [str(p.relative_to(out)) for p in picked],
            "reported": sum(str(p) in warned for p in picked),
            "exit": code,
            "differences": runs.differences(ref, out) if code == 0 else [err.strip()[-300:]],
            "bad_entries": runs.bad_entries(cache),
        }
        row["ok"] = code == 0 and row["reported"] == len(picked) and not row["differences"] and not row["bad_entries"]
        log(f"corruption round {r + 1}: {len(picked)} planted, {row['reported']} reported and recomputed"
            f" -> {'ok' if row['ok'] else 'FAILED ' + json.dumps(row)}")
        rows.append(row)
        r += 1
    return rows


def needs_root():
    return os.geteuid() != 0
