"""Running `gait` for the fault-injection script, and checking what a run left behind: results
the same as the undisturbed run's, no half-written file under a final name, every cache entry
whole (its SHA-256 footer checks)."""
import hashlib
import json
import os
import pathlib
import re
import signal
import subprocess
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
SAMPLE = (ROOT / "../shared/data/sports2d-demo.mp4").resolve()
TINY = ROOT / "crates/gait-diffuse/tests/fixtures/tiny"
ENTRY = re.compile(r"^\d{6}\.(json|png|state)$")
SUM_TAG = b"\ngait-sha256:"


class Gait:
    """The `gait` binary, the models folder and the pipeline every run of the script uses: the
    walker's frames of the sample video redrawn by the tiny random SD 1.5 + ControlNet (so the
    regeneration step is the real code), with the overlay video, the PDF and the exports on."""

    def __init__(self, exe, models, frames):
        self.exe, self.models = str(exe), str(models)
        first = 90
        self.sets = [
            f"input.first_frame={first}",
            f"input.last_frame={first + frames - 1}",
            'edge.kind="canny"',
            'regenerator.kind="controlnet"',
            "regenerator.resolution=64",
            "regenerator.steps=2",
            f'regenerator.sd_path="{TINY}"',
            f'regenerator.controlnet_path="{TINY / "controlnet"}"',
        ]
        self.frames = frames

    def run_args(self, out, extra_sets=()):
        args = [self.exe, "--models-dir", self.models, "run", "--no-progress"]
        args += ["--input", str(SAMPLE), "--out", str(out)]
        for s in [*self.sets, *extra_sets]:
            args += ["--set", s]
        return args

    def start(self, out, extra_sets=()):
        """A run in its own process group (so its ffmpeg and Chromium can be cleaned up)."""
        return subprocess.Popen(
            self.run_args(out, extra_sets),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )

    def run(self, out, extra_sets=()):
        p = subprocess.run(self.run_args(out, extra_sets), capture_output=True, text=True)
        return p.returncode, p.stderr

    def study_sets(self):
        """The pipeline as a study file's `set` column."""
        return ";".join(self.sets)


def stop_group(proc):
    """Whatever the killed run started (ffmpeg, Chromium) goes too."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def entries(cache):
    """Every cache entry under `cache` (stage folders of NNNNNN.json/png/state)."""
    cache = pathlib.Path(cache)
    if not cache.is_dir():
        return []
    return [f for d in cache.iterdir() if d.is_dir() for f in d.iterdir() if ENTRY.match(f.name)]


def entry_ok(path):
    data = path.read_bytes()
    at = data.rfind(SUM_TAG)
    if at < 0 or len(data) != at + len(SUM_TAG) + 17:
        return False
    return hashlib.sha256(data[:at]).hexdigest()[:16].encode() == data[at + len(SUM_TAG):-1]


def bad_entries(cache):
    return [str(f) for f in entries(cache) if not entry_ok(f)]


def count(cache, stage):
    """Entries of one stage's folder(s), e.g. "regenerator" (its .png frames)."""
    cache = pathlib.Path(cache)
    if not cache.is_dir():
        return 0
    ext = {"regenerator": ".png", "edge": ".png"}.get(stage, ".json")
    return sum(
        1
        for d in cache.iterdir()
        if d.name.startswith(stage + "-")
        for f in d.iterdir()
        if ENTRY.match(f.name) and f.suffix == ext
    )


def _manifest(text, run_dir):
    """run.json without what records how the run went (timings, cache hits, the folder, the
    warnings of corrupt entries found) rather than what it found."""

    def clean(v):
        if isinstance(v, dict):
            # backend_choices: how `auto` was decided, at the run or when a batch planned it.
            drop = {"command", "started_unix", "seconds", "cached", "computed", "frames_from_cache",
                    "timings", "backend_choices"}
            return {k: clean(x) for k, x in v.items() if k not in drop}
        if isinstance(v, list):
            return [clean(x) for x in v if not (isinstance(x, str) and "failed its checksum" in x)]
        return v

    v = json.loads(text.replace(str(pathlib.Path(run_dir).resolve()), "@RUN@"))
    v.get("config", {}).get("run", {}).pop("cache_dir", None)
    # A study row declares its view (the study's `view` column), the undisturbed `gait run`
    # decides it from the keypoints: the same analysis, recorded as declared or as decided.
    v.get("config", {}).get("kinematics", {}).pop("view", None)
    v.get("kinematics", {}).pop("view", None)
    v.get("extra", {}).get("kinematics", {}).pop("view", None)
    return clean(v)


def _report(text, run_dir):
    text = text.replace(str(pathlib.Path(run_dir).resolve()), "@RUN@")
    # The provenance (run date) and the folded manifest differ between runs of the same input.
    text = re.sub(r"<h2 id=\"provenance\">Provenance</h2>.*?</details>", "", text, flags=re.S)
    # A study row declares its view, the undisturbed `gait run` decides it (as in run.json above).
    text = re.sub(r"<li>View: [^<]*</li>", "", text)
    return re.sub(r"<li>cache entry [^<]*failed its checksum[^<]*</li>", "", text)


def pdf_whole(path):
    data = path.read_bytes()
    return data.startswith(b"%PDF") and data.rstrip().endswith(b"%%EOF")


def results(run_dir):
    return sorted(p.name for p in pathlib.Path(run_dir).iterdir() if p.is_file() and not p.name.startswith("."))


def differences(ref, run):
    """Files of `run` that differ from the undisturbed `ref` (empty: the same results)."""
    ref, run = pathlib.Path(ref), pathlib.Path(run)
    out = []
    names = results(ref)
    if results(run) != names:
        return [f"files {sorted(set(names) ^ set(results(run)))}"]
    for name in names:
        a, b = ref / name, run / name
        if name == "run.json":
            same = _manifest(a.read_text(), ref) == _manifest(b.read_text(), run)
        elif name == "report.html":
            same = _report(a.read_text(), ref) == _report(b.read_text(), run)
        elif name == "report.pdf":
            # It prints run.json's timings and the date: whole, not compared.
            same = pdf_whole(b)
        else:
            same = a.read_bytes() == b.read_bytes()
        if not same:
            out.append(name)
    return out


def partial_files(ref, run):
    """Files under a final name in a stopped run that are not whole: each must equal the
    undisturbed run's (run.json: valid JSON; report.pdf: a whole PDF)."""
    ref, run = pathlib.Path(ref), pathlib.Path(run)
    bad = []
    if not run.is_dir():
        return bad
    for name in results(run):
        b = run / name
        if name == "run.json":
            try:
                json.loads(b.read_text())
            except ValueError:
                bad.append(name)
        elif name == "report.pdf":
            if not pdf_whole(b):
                bad.append(name)
        elif name == "report.html":
            if not b.read_text().rstrip().endswith("</html>"):
                bad.append(name)
        elif not (ref / name).is_file() or (ref / name).read_bytes() != b.read_bytes():
            bad.append(name)
    return bad


def wait_for(pred, proc=None, timeout=300, every=0.02):
    """Polls `pred` until true; False when `proc` ended first or on timeout."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        if proc is not None and proc.poll() is not None:
            return False
        time.sleep(every)
    return False
