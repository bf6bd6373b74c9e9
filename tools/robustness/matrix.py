#!/usr/bin/env python3
"""Robustness matrix (issue 37): the same walk, re-encoded, resampled, rescaled, mirrored,
relit, noised and cut with ffmpeg, each variant through the default pipeline, compared with the
original in seconds; then `gait kin` on the original's keypoints with Gaussian noise of 1, 2 and
3 px (several seeds), and the pose model's other backend against the default's; and from all of them the minimal
detectable change of every reported measure (mdc.py). Exits 1 when a decision target (events,
bouts, cycles) is missed on a variant the run was asked to hold (--hold; `noise` holds the 2 px
noise runs to 9 of 10 seeds), else 0; the tables are written either way.

    python3 tools/robustness/matrix.py --gait target/debug/gait [--input VIDEO] [--work DIR]
        [--mode quick|full] [--variants a,b] [--seeds N] [--hold a,b,noise|all] [--json F] [--md F]
        [--set key=value ...]

quick (tools/test.sh): the variants of variants.QUICK, 2 px noise with 5 seeds; full
(BENCHMARKS.md): every variant, 1/2/3 px with 10 seeds each, and ort against candle. Runs are
made without the overlay and the PDF (they do not change a number); a second call reuses the
variants' videos and the runs' caches, so it takes seconds."""
import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).parent))

import compare  # noqa: E402
import mdc  # noqa: E402
import noise  # noqa: E402
import variants  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
FAST = ["--set", "report.overlay=false", "--set", "report.pdf=false", "--set", "export.formats=[]",
        "--no-progress"]
# Settings of every run of this call (`--set`): the matrix of a configuration other than the default.
SETTINGS = []


def copies_args(doc, work):
    """The command line of the scripts that run copies of one video (blur.py, motion_blur.py):
    (gait binary, work folder made, input video), resolved."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--gait", required=True)
    ap.add_argument("--input", default=str(ROOT / "data/sample/sports2d-demo.mp4"))
    ap.add_argument("--work", default=str(ROOT / work))
    a = ap.parse_args()
    folder = pathlib.Path(a.work).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    return pathlib.Path(a.gait).resolve(), folder, pathlib.Path(a.input).resolve()


def run(gait, video, out, extra=()):
    """`gait run` into `out`; stderr lines returned. A folder of an earlier call keeps its cache,
    so only the stages whose inputs changed run again (the kinematics always do)."""
    cmd = [str(gait), "run", "--input", str(video), "--out", str(out)] + FAST + SETTINGS + list(extra)
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"matrix: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()[-2000:]}")
    return p.stderr.splitlines()


def kin(gait, keypoints, out):
    """`gait kin` on a keypoints CSV, with the run's fps and frame size from the run.json beside it."""
    cmd = [str(gait), "kin", "--keypoints", str(keypoints), "--out", str(out)]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"matrix: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()[-2000:]}")


def fps_of(folder):
    return json.loads((folder / "run.json").read_text())["input"]["fps"]


def width_of(folder):
    return json.loads((folder / "run.json").read_text())["input"]["width"]


def load(folder, v=None, base_width=None):
    scale = 1.0
    if v is not None and v.scale is None:
        scale = width_of(folder) / base_width
    return compare.load(folder, fps_of(folder), v.offset_s if v else 0.0,
                        v.mirrored if v else False, scale)


def noise_runs(gait, ref_dir, work, sigmas, seeds, tol_s, log):
    """`gait kin` on the original's keypoints, clean and with noise; comparisons per sigma."""
    clean = work / "kin_clean"
    kin(gait, ref_dir / "keypoints.csv", clean)
    # The noisy copies sit beside a copy of run.json, so `gait kin` finds fps and frame size.
    out = {}
    base = compare.load(clean, fps_of(ref_dir))
    samples = []
    for sigma in sigmas:
        rows = []
        for seed in range(seeds):
            d = work / f"noise_{sigma}px_{seed}"
            d.mkdir(parents=True, exist_ok=True)
            shutil.copy(ref_dir / "run.json", d / "run.json")
            noise.jitter(ref_dir / "keypoints.csv", d / "keypoints.csv", sigma, 1000 * sigma + seed)
            kin(gait, d / "keypoints.csv", d / "kin")
            c = compare.compare(base, compare.load(d / "kin", fps_of(ref_dir)), tol_s)
            c["fails"] = compare.verdict(c)
            rows.append(c)
            samples.append(mdc.measures(d / "kin", fps_of(ref_dir)))
        ok = sum(1 for c in rows if not c["fails"]["decisions"])
        every = sum(1 for c in rows if not compare.failed(c["fails"]))
        log(f"noise {sigma} px: decisions held in {ok} of {seeds} seeds, every target in {every}")
        out[f"{sigma}px"] = {"seeds": seeds, "decisions_held": ok, "meeting_targets": every, "runs": rows}
    return out, samples


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gait", required=True)
    ap.add_argument("--input", default=str(ROOT / "data/sample/sports2d-demo.mp4"))
    ap.add_argument("--work", default=str(ROOT / "target/robustness"))
    ap.add_argument("--mode", choices=["quick", "full"], default="quick")
    ap.add_argument("--variants", help="comma-separated names (default: the mode's)")
    ap.add_argument("--seeds", type=int)
    ap.add_argument("--hold", default="", help="variants whose misses fail the run ('all': every one)")
    ap.add_argument("--tolerance-s", type=float, default=1 / 30)
    ap.add_argument("--json")
    ap.add_argument("--md")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a setting for every run (an ablation: the matrix of another configuration)")
    a = ap.parse_args()
    for kv in a.set:
        SETTINGS.extend(["--set", kv])
    gait = pathlib.Path(a.gait).resolve()
    work = pathlib.Path(a.work).resolve()
    (work / "videos").mkdir(parents=True, exist_ok=True)
    started = time.monotonic()

    def log(line):
        print(f"[{time.monotonic() - started:6.0f} s] {line}", flush=True)

    original = pathlib.Path(a.input).resolve()
    w, h, fps, frames = variants.probe(original)
    cat = {v.name: v for v in variants.catalogue(frames / fps, h)}
    names = a.variants.split(",") if a.variants else (variants.QUICK if a.mode == "quick" else list(cat))
    unknown = [n for n in names if n not in cat]
    if unknown:
        sys.exit(f"matrix: unknown variant(s) {unknown}; known: {', '.join(cat)}")
    ref_dir = work / "original"
    run(gait, original, ref_dir)
    ref = load(ref_dir)
    log(f"original: {len(ref.events)} events, {len(ref.cycles)} accepted cycles, bouts {ref.bouts}")
    results = {"input": str(original), "mode": a.mode, "tolerance_s": a.tolerance_s, "variants": {}}
    samples = [mdc.measures(ref_dir, fps_of(ref_dir))]
    for name in names:
        v = cat[name]
        t0 = time.monotonic()
        video = variants.make(original, v, work / "videos")
        made = time.monotonic() - t0
        warnings = run(gait, video, work / name)
        c = compare.compare(ref, load(work / name, v, w), a.tolerance_s)
        scale = 1.0 if v.scale is not None else width_of(work / name) / w
        samples.append(mdc.measures(work / name, fps_of(work / name), v.offset_s, v.mirrored, scale))
        c["what"] = v.what
        c["fails"] = compare.verdict(c)
        c["warnings"] = [x for x in warnings if x.startswith("warning:")]
        c["encode_s"] = round(made, 1)
        c["run_s"] = round(time.monotonic() - t0 - made, 1)
        results["variants"][name] = c
        log(f"{name}: {summary(c['fails'])}")
    sigmas = [2] if a.mode == "quick" else [1, 2, 3]
    seeds = a.seeds or (5 if a.mode == "quick" else 10)
    results["noise"], noisy_samples = noise_runs(gait, ref_dir, work, sigmas, seeds, a.tolerance_s, log)
    samples += noisy_samples
    if a.mode == "full":
        # The other backend of the pose model against the one the default ran on
        # (backend = "auto": ort where ONNX Runtime loads, else candle).
        ran = json.loads((ref_dir / "run.json").read_text())["config"]["pose"]["backend"]
        other = "candle" if ran == "ort" else "ort"
        run(gait, original, work / other, ["--set", f"pose.backend={other}"])
        c = compare.compare(ref, load(work / other), a.tolerance_s)
        c["fails"] = compare.verdict(c)
        c["what"] = f"{other} backend vs {ran}"
        results["other_backend"] = c
        log(f"{other} vs {ran}: {summary(c['fails'])}")
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(results, indent=1))
    rows = mdc.table(samples)
    mdc.write_csv(rows, work / "mdc.csv")
    table = markdown(results) + "\n" + mdc.markdown(rows)
    if a.md:
        pathlib.Path(a.md).write_text(table)
    print(table)
    hold = names + ["noise"] if a.hold == "all" else [x for x in a.hold.split(",") if x]
    failed = [n for n in hold if results["variants"].get(n, {}).get("fails", {}).get("decisions")]
    noisy = results["noise"].get("2px")
    if noisy and "noise" in hold and noisy["decisions_held"] < 0.9 * noisy["seeds"]:
        failed.append("2 px noise")
    if failed:
        sys.exit(f"matrix: decisions tipped on {', '.join(failed)} (see {work})")


def summary(fails):
    every = compare.failed(fails)
    return "meets every target" if not every else "; ".join(every)


def markdown(r):
    """The table of BENCHMARKS.md and the README's reliability section."""
    out = ["| variant | events within 33 ms | missing / extra in bouts | max event error (ms) | "
           "accepted cycles | curve RMS (deg): mean over joints / worst | worst parameter change | decisions | "
           "precision |",
           "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]

    def row(name, c):
        rms = [v for v in c["curve_rms_deg"].values() if v == v]
        worst_rms = max(rms, default=float("nan"))
        mean_rms = sum(rms) / len(rms) if rms else float("nan")
        rel = [(v["rel"] * 100, k) for k, v in c["params"].items() if "rel" in v]
        worst = max(rel, default=(float("nan"), ""))
        err = c["max_event_error_s"]
        out.append(
            f"| {name} | {c['events_within_tol']} of {c['events_ref']} | "
            f"{len(c['missing_events'])} / {len(c['extra_events'])} | "
            f"{'' if err is None else round(err * 1000)} | {c['cycles_var']} (original {c['cycles_ref']}) | "
            f"{mean_rms:.2f} / {worst_rms:.2f} | {worst[0]:.1f} % ({worst[1]}) | "
            f"{'held' if not c['fails']['decisions'] else '; '.join(c['fails']['decisions'])} | "
            f"{'met' if not c['fails']['precision'] else '; '.join(c['fails']['precision'])} |")

    for name, c in r["variants"].items():
        row(f"{name}: {c['what']}", c)
    if "other_backend" in r:
        row(r["other_backend"]["what"], r["other_backend"])
    for sigma, n in r.get("noise", {}).items():
        out.append(f"| keypoint noise {sigma} | | | | | | | decisions held in {n['decisions_held']} of "
                   f"{n['seeds']} seeds | every target in {n['meeting_targets']} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    os.environ.setdefault("GAIT_NO_PROGRESS", "1")
    main()
