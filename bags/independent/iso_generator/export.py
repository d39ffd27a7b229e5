"""The tracker software's CSV export, the mapping file that reads it into metrocell's point
layout (crates/bagtools/src/import.rs, module doc), and the user's model file.

The export is ours, as a tracker package would write it: millimetres, a U95 (k = 2) per point,
a UTC date-time stamp, temperatures in °C from the logger's channels, station air in hPa and
%RH, axis feeds in mm/s, approach flags as "+"/"-" direction columns. The mapping converts
each of our columns (value_SI = raw·scale + offset).
"""

import csv
import datetime as dt

import numpy as np


class Column:
    """One column of the export: header, the values (N,), a formatter, and where the mapping
    sends it (layout key, scale to SI)."""

    def __init__(self, header, values, fmt, key=None, scale=None):
        self.header, self.values, self.fmt, self.key, self.scale = header, values, fmt, key, scale


def utc_stamp(epoch_s):
    """2025-06-17 06:02:13.250 — the layout's UTC date-time form with a space, no Z."""
    return dt.datetime.fromtimestamp(float(epoch_s), dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]


def mm(v, digits=4):
    return "" if not np.isfinite(v) else f"{v * 1000.0:.{digits}f}"


def fixed(digits):
    return lambda v: "" if not np.isfinite(v) else f"{v:.{digits}f}"


def write_csv(path, columns):
    n = len(columns[0].values)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([c.header for c in columns])
        for i in range(n):
            w.writerow([c.fmt(c.values[i]) for c in columns])


def write_mapping(path, columns, source, frame_id="tracker", comment=""):
    lines = [f"# {line}" for line in comment.strip().splitlines()] if comment else []
    lines += [f"frame_id: {frame_id}", f"source: {source}", "columns:"]
    ignored = []
    for c in columns:
        if c.key is None:
            ignored.append(c.header)
            continue
        spec = f'{{column: "{c.header}"' + (f", scale: {c.scale!r}" if c.scale is not None else "") + "}"
        lines.append(f"  {c.key}: {spec}")
    if ignored:
        lines.append("ignore: [" + ", ".join(f'"{h}"' for h in ignored) + "]")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def yaml_mm(v):
    return f"{v * 1000.0:.3f} mm"
