"""Two writers at once: a second `gait run` or `gait batch` on a folder in use (refused at
once, naming the holder's pid), several runs sharing one cache folder, and the parts of a
`--split-frames` study writing one cache concurrently (no entry ever corrupt)."""
import json
import subprocess
import time

import runs


def _second_writer(gait, ref, work, i, log, batch):
    out = work / f"race{i}"
    if batch:
        study = write_study(gait, work / f"race{i}-study.csv", 1)
        first = subprocess.Popen(batch_args(gait, study, out, []), stderr=subprocess.PIPE, start_new_session=True)
        second_args = batch_args(gait, study, out, [])
        lock = out / ".gait.lock"
    else:
        first = gait.start(out)
        second_args = gait.run_args(out)
        lock = out / ".gait.lock"
    runs.wait_for(lambda: lock.exists() and lock.read_text().startswith(str(first.pid)), first, timeout=60)
    t = time.monotonic()
    second = subprocess.run(second_args, capture_output=True, text=True)
    took = time.monotonic() - t
    code = first.wait()
    row = {
        "what": "gait batch" if batch else "gait run",
        "second_exit": second.returncode,
        "second_error": second.stderr.strip(),
        "refused_in_s": round(took, 2),
        "first_exit": code,
    }
    row["names_pid"] = str(first.pid) in second.stderr and len(second.stderr.strip().splitlines()) == 1
    result = out / "runs" / _row_name() if batch else out
    row["differences"] = runs.differences(ref, result) if code == 0 else ["first run failed"]
    row["ok"] = second.returncode == 2 and row["names_pid"] and took < 5 and code == 0 and not row["differences"]
    log(f"race {i + 1}: a second {row['what']} on a folder in use: exit {row['second_exit']} in {took:.2f} s"
        f" -> {'ok' if row['ok'] else 'FAILED ' + json.dumps(row)}")
    return row


def _shared_cache(gait, ref, work, i, log, writers):
    cache = work / f"race{i}-cache"
    procs = [
        (gait.start(work / f"race{i}-{k}", [f'run.cache_dir="{cache}"']), work / f"race{i}-{k}")
        for k in range(writers)
    ]
    codes = [p.wait() for p, _ in procs]
    row = {"what": f"{writers} runs writing one cache", "exits": codes, "bad_entries": runs.bad_entries(cache)}
    row["differences"] = [d for (_, out) in procs for d in runs.differences(ref, out)]
    row["ok"] = codes == [0] * writers and not row["bad_entries"] and not row["differences"]
    log(f"race {i + 1}: {row['what']}: exits {codes}, {len(runs.entries(cache))} entries, "
        f"{len(row['bad_entries'])} bad -> {'ok' if row['ok'] else 'FAILED ' + json.dumps(row)}")
    return row


def _split(gait, ref, work, i, log, parts):
    study = write_study(gait, work / f"race{i}-study.csv", 1)
    out = work / f"race{i}"
    done = subprocess.run(
        batch_args(gait, study, out, ["--split-frames", str(parts), "--jobs", str(parts)]),
        capture_output=True,
        text=True,
    )
    row = {"what": f"--split-frames {parts}: parts writing one cache", "exit": done.returncode}
    row["bad_entries"] = runs.bad_entries(out / "cache")
    row["differences"] = runs.differences(ref, out / "runs" / _row_name()) if done.returncode == 0 else [done.stderr[-300:]]
    row["ok"] = done.returncode == 0 and not row["bad_entries"] and not row["differences"]
    log(f"race {i + 1}: {row['what']}: exit {done.returncode}, {len(row['bad_entries'])} bad entries"
        f" -> {'ok' if row['ok'] else 'FAILED ' + json.dumps(row)}")
    return row


def _row_name():
    return "S01_1_left_sports2d-demo"


def write_study(gait, path, rows, row_sets=lambda r: []):
    """A study file of `rows` rows of the script's pipeline (sessions 1, 2, ...), each with
    `row_sets(r)` added to its `set` column."""
    lines = ["video,subject,session,view,prosthetic_side,config,set"]
    for r in range(rows):
        sets = ";".join([gait.study_sets(), *row_sets(r)]).replace('"', '""')
        lines.append(f'{runs.SAMPLE},S01,{r + 1},left,,,"{sets}"')
    path.write_text("\n".join(lines) + "\n")
    return path


def batch_args(gait, study, out, extra):
    return [gait.exe, "--models-dir", gait.models, "batch", str(study), "--out", str(out), *extra]


def run(gait, ref, work, log):
    """Ten races: 3 second `gait run`s, 2 second `gait batch`es, 3 x 4 runs on one cache,
    2 split studies (3 parts)."""
    rows = []
    for i in range(10):
        if i < 3:
            rows.append(_second_writer(gait, ref, work, i, log, batch=False))
        elif i < 5:
            rows.append(_second_writer(gait, ref, work, i, log, batch=True))
        elif i < 8:
            rows.append(_shared_cache(gait, ref, work, i, log, writers=4))
        else:
            rows.append(_split(gait, ref, work, i, log, parts=3))
    return rows

