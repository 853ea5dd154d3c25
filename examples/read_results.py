#!/usr/bin/python3
"""Reading flume's results from Python: a run's result.h5 (h5py, pandas) and a campaign database (sqlite3).

    /usr/bin/python3 examples/read_results.py RUN_DIR [RUN_DIR ...] [--db CAMPAIGN.db]

For each run it prints, per gauge, the peak and the arrival exactly as `flume gauges RUN_DIR ...` prints them;
for the database, the table `flume campaign export --db CAMPAIGN.db --csv -` prints (tests/examples checks
both). The layout of the files is in docs/results.md. Debian packages: python3-h5py python3-pandas.
"""
import argparse
import math
import os
import re
import sqlite3
import sys

import h5py
import pandas as pd

ARRIVAL_THRESHOLD_M = 0.005  # 5 mm above the first reading, as `flume run` and `flume gauges` have it


def natural_key(name):
    """WG2 before WG10, as `flume gauges` sorts them."""
    return [(0, int(p), p) if p.isdigit() else (1, 0, p) for p in re.split(r"(\d+)", name) if p]


def read_gauges(run_dir):
    """{gauge name: DataFrame(time, elevation)} of a finished run (SI units: s, m)."""
    with h5py.File(os.path.join(run_dir, "result.h5"), "r") as f:
        print(f"# {run_dir}: scene {f.attrs['scene']!r}, {int(f.attrs['dimension'])}D, dx {f.attrs['dx']} m, "
              f"status {f.attrs['status']}", file=sys.stderr)
        return {name: pd.DataFrame({"time": g["time"][:], "elevation": g["elevation"][:]})
                for name, g in f["gauges"].items()}


def gauge_summary(df):
    """Peak (first maximum), its time and the arrival, skipping non-finite samples (solver/run_output.cpp)."""
    finite = df[df["elevation"].map(math.isfinite)]
    if finite.empty:
        return None
    first = finite["elevation"].iloc[0]
    peak_row = finite.loc[finite["elevation"].idxmax()]
    arrived = finite[finite["elevation"] >= first + ARRIVAL_THRESHOLD_M]
    arrival = arrived["time"].iloc[0] if not arrived.empty else None
    return first, peak_row["elevation"], peak_row["time"], arrival


def print_run(run_dir):
    label = os.path.basename(os.path.normpath(os.path.abspath(run_dir)))
    for name, df in sorted(read_gauges(run_dir).items(), key=lambda kv: natural_key(kv[0])):
        s = gauge_summary(df)
        if s is None:
            print(f"{name} {label}: peak none (no finite sample), arrival none")
            continue
        first, peak, peak_time, arrival = s
        line = f"{name} {label}: peak {peak + 0.0:.4f} m at {peak_time:.3f} s"
        if arrival is not None:
            line += f", arrival {arrival:.3f} s (5 mm above the first reading, {first + 0.0:.4f} m)"
        else:
            line += f", arrival none (never 5 mm above the first reading, {first + 0.0:.4f} m)"
        print(line)


def number(v):
    """The shortest of %.15g, %.16g, %.17g that reads back as v (what the store's CSV export writes)."""
    for precision in (15, 16, 17):
        s = "%.*g" % (precision, v)
        if float(s) == v:
            return s
    return s


def csv_field(s):
    if not any(c in s for c in ',"\n\r'):
        return s
    return '"' + s.replace('"', '""') + '"'


def print_campaigns(db_file):
    """Every campaign's results view (one row per design point), as one CSV with the union of the columns."""
    db = sqlite3.connect(f"file:{db_file}?mode=ro", uri=True)
    header, rows = ["campaign"], []
    for cid, name in db.execute("SELECT id, name FROM campaigns ORDER BY id"):
        cur = db.execute(f'SELECT * FROM "results_{name.replace(chr(34), chr(34) * 2)}"')
        cols = [d[0] for d in cur.description]
        header += [c for c in cols if c not in header]
        for r in cur:
            row = {"campaign": name}
            for c, v in zip(cols, r):
                if v is not None:
                    row[c] = number(v) if isinstance(v, float) else str(v)
            rows.append(row)
    print(",".join(csv_field(h) for h in header))
    for row in rows:
        print(",".join(csv_field(row[h]) if h in row else "" for h in header))
    # The same view as a DataFrame, for analysis: one column per parameter and per metric.
    for (name,) in db.execute("SELECT name FROM campaigns ORDER BY id"):
        df = pd.read_sql_query(f'SELECT * FROM "results_{name}"', db)
        print(f"# campaign {name}: {len(df)} runs, {int((df['status'] == 'ok').sum())} ok", file=sys.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*", metavar="RUN_DIR")
    ap.add_argument("--db", help="a campaign database (flume campaign run ... --db FILE)")
    a = ap.parse_args()
    for run_dir in a.runs:
        print_run(run_dir)
    if a.db:
        print_campaigns(a.db)


if __name__ == "__main__":
    main()
