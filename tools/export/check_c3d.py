#!/usr/bin/env python3
"""Read a C3D file with ezc3d (the reference reader) and print what it found as JSON.

Usage (from the repository root):

    PY=$(bash tools/export/setup_ezc3d.sh)   # venv with the pinned ezc3d
    "$PY" tools/export/check_c3d.py FILE.c3d

crates/gait-c3d/tests/ezc3d.rs runs it on the files gait-c3d writes. The JSON object has:
  ezc3d_version   version of the ezc3d that read the file
  labels          POINT:LABELS, one per marker
  rate            POINT:RATE (frames per second); header_rate is the header's copy
  first_frame     first frame number, 1-based as C3D counts (ezc3d's header value is 0-based)
  last_frame      last frame number, 1-based
  frames          number of frames in the data
  units           POINT:UNITS
  points          [marker][frame] -> [x, y, z]; a coordinate ezc3d gives as NaN is null
  residuals       [marker][frame] -> residual as ezc3d reports it (negative = missing)
  analog_used     ANALOG:USED; analog_channels: channels in ezc3d's analog data
  events          list of {context, label, description, icon_id, generic_flag, minutes,
                  seconds, time_s}, from the EVENT group; time_s = minutes * 60 + seconds
"""
import json
import math
import sys

import ezc3d


def finite_or_none(v):
    v = float(v)
    return None if math.isnan(v) else v


def values(params, group, name, default=()):
    """A parameter's values as a list, or `default` when the group or parameter is absent."""
    try:
        v = params[group][name]["value"]
    except KeyError:
        return list(default)
    return v.tolist() if hasattr(v, "tolist") else list(v)


def main(path):
    c = ezc3d.c3d(path)
    params, header, data = c["parameters"], c["header"], c["data"]
    points = data["points"]  # shape (4, markers, frames): x, y, z, 1
    residuals = data["meta_points"]["residuals"]  # shape (1, markers, frames)
    n_markers, n_frames = points.shape[1], points.shape[2]

    n_events = int(values(params, "EVENT", "USED", [0])[0])
    times = values(params, "EVENT", "TIMES")  # 2 x N: [minutes..], [seconds..]
    contexts = values(params, "EVENT", "CONTEXTS")
    labels = values(params, "EVENT", "LABELS")
    descriptions = values(params, "EVENT", "DESCRIPTIONS")
    icons = values(params, "EVENT", "ICON_IDS")
    flags = values(params, "EVENT", "GENERIC_FLAGS")
    events = []
    for i in range(n_events):
        minutes, seconds = float(times[0][i]), float(times[1][i])
        events.append({
            "context": contexts[i],
            "label": labels[i],
            "description": descriptions[i] if i < len(descriptions) else None,
            "icon_id": int(icons[i]) if i < len(icons) else None,
            "generic_flag": int(flags[i]) if i < len(flags) else None,
            "minutes": minutes,
            "seconds": seconds,
            "time_s": minutes * 60.0 + seconds,
        })

    out = {
        "ezc3d_version": getattr(ezc3d, "__version__", None),
        "labels": values(params, "POINT", "LABELS"),
        "rate": float((values(params, "POINT", "RATE") or [math.nan])[0]),
        "header_rate": float(header["points"]["frame_rate"]),
        "first_frame": int(header["points"]["first_frame"]) + 1,
        "last_frame": int(header["points"]["last_frame"]) + 1,
        "frames": int(n_frames),
        "units": (values(params, "POINT", "UNITS") or [None])[0],
        "points": [[[finite_or_none(points[k, m, f]) for k in range(3)] for f in range(n_frames)]
                   for m in range(n_markers)],
        "residuals": [[float(residuals[0, m, f]) for f in range(n_frames)] for m in range(n_markers)],
        "analog_used": int(values(params, "ANALOG", "USED", [0])[0]),
        "analog_channels": int(data["analogs"].shape[1]),
        "events": events,
    }
    json.dump(out, sys.stdout, allow_nan=False)
    sys.stdout.write("\n")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
