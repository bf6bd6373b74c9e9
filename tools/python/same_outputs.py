"""Whether two run folders hold the same results: every file byte for byte, except what
records how the run went rather than what it found: run.json without `command`,
`started_unix` and the steps' `seconds`; report.html the same where it prints run.json.
report.pdf prints that too (and its dates), so two `gait run`s of one input differ there
as well: it is listed, not compared. Prints one line per file; exits 1 when any differs."""
import json
import pathlib
import re
import sys

a, b = (pathlib.Path(p) for p in sys.argv[1:3])


def without_timing(value):
    if isinstance(value, dict):
        return {
            k: without_timing(v)
            for k, v in value.items()
            if k not in ("command", "started_unix", "seconds")
        }
    if isinstance(value, list):
        return [without_timing(v) for v in value]
    return value


def manifest(path):
    return without_timing(json.loads(path.read_text()))


def report(path):
    text = path.read_text()
    text = re.sub(r"&quot;command&quot;: \[.*?\],", "", text, flags=re.S)
    text = re.sub(r"&quot;(started_unix|seconds)&quot;: [0-9.e+-]+", "", text)
    # A step's seconds are an object in the report's run.json listing.
    text = re.sub(r"&quot;seconds&quot;: \{.*?\}", "", text, flags=re.S)
    return text


compare = {"run.json": manifest, "report.html": report, "report.pdf": lambda p: b""}
names = sorted(p.name for p in a.iterdir() if p.is_file())
if names != sorted(p.name for p in b.iterdir() if p.is_file()):
    print("different files:", names, sorted(p.name for p in b.iterdir() if p.is_file()))
    sys.exit(1)
bad = 0
for name in names:
    read = compare.get(name, lambda p: p.read_bytes())
    same = read(a / name) == read(b / name)
    bad += not same
    label = "not compared (prints timings) " if name == "report.pdf" else "same "
    print((label if same else "DIFFERENT ") + name)
print(f"{len(names) - bad} of {len(names)} files identical")
sys.exit(1 if bad else 0)
