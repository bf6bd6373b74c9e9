#!/usr/bin/env python3
"""Derive a sagittal DeepLabCut-layout CSV from the Parkinson's disease example trial in gaitkit.

Source: `gaitkit==1.5.0` sdist on PyPI (MIT-licensed package), file
`src/gaitkit/data/example_parkinson.json` (identical in gaitkit 0.1.0, 1.2.4, 1.3.1 and 1.4.9).
sha256 of `gaitkit-1.5.0.tar.gz`: de1f0c258152c5eac2e3d0382fb57e321c69091ee7923ce0849ff24d9640d861.
One overground walking trial of a person with Parkinson's disease, 150 Hz, annotated heel strikes
and toe-offs. gaitkit's own metadata is inconsistent about where it comes from (see
tests/data/gaitkit_pd/README.md): the JSON names "Goldberger et al., PhysioNet Gait in PD, ODC-By
1.0" and doi 10.6084/m9.figshare.7734767, while gaitkit's extractor for this data
(`extractors/figshare_pd_extractor.py`) reads the C3D files of Shida et al. 2023, "A public data
set of walking full-body kinematics and kinetics in individuals with Parkinson's disease",
Front. Neurosci. 17:992585 (figshare 14896881). Either way it is distributed under an open
attribution licence; we keep the attribution in the README.

Needs only the Python standard library. Regenerate:

    pip download --no-deps --no-binary=:all: gaitkit==1.5.0   # or copy the sdist from pip's cache
    tar xzf gaitkit-1.5.0.tar.gz
    python3 tools/kin/derive_gaitkit_pd.py gaitkit-1.5.0/src/gaitkit/data/example_parkinson.json tests/data/gaitkit_pd

Projection (as tools/kin/derive_fukuchi.py): lab x = walking direction, y = up, z = mediolateral
(right is +z). A camera on the subject's right sees image x = lab x, image y = -lab y; 1 px = 2 mm,
    u = (X - min X) / 2 + 50,  v = (max Y - Y) / 2 + 50,  likelihood 1 (no gaps in this trial).

Writes keypoints.csv (DeepLabCut layout, 10 lower-limb keypoints), events.csv
(side,event,frame,time_s: the file's annotated events) and reference.csv (the file's angles).
"""
import sys
from pathlib import Path

# Same file format as the Fukuchi trial: one derivation for both.
sys.path.insert(0, str(Path(__file__).resolve().parent))
from derive_fukuchi import main as derive  # noqa: E402


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    derive(sys.argv[1], sys.argv[2], scorer="gaitkit_pd_mocap")
