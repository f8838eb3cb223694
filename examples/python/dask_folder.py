"""Measure every shot in a folder with Dask and write one summary table.

    pip install ./python "dask[bag]" pandas
    python examples/python/dask_folder.py SHOTS_DIR --target targets/a4_log.toml -o summary.csv

One row per shot: the shot, MTF50/MTF30/MTF10 (cycles/pixel), MTF at Nyquist,
chart modulation, the warnings, or the error that stopped it (a shot that
cannot be measured is a row with its error, not a failed run). dask.bag runs
the shots on a process pool here; on a cluster, create a
``dask.distributed.Client`` first and the same code spreads over its
workers. The library releases the GIL, so a threaded scheduler also uses
every core: ``--scheduler threads``.
"""

import argparse
import csv
import os
import sys

import dask.bag as db

import sweepmtf

PHOTO_EXTS = {".jpg", ".jpeg", ".png", ".tif", ".tiff", ".dng", ".nef", ".cr2", ".arw"}
COLUMNS = ["shot", "channel", "sweep", "mtf50_cy_px", "mtf30_cy_px", "mtf10_cy_px",
           "mtf_nyquist", "chart_modulation", "warnings", "error"]


def measure_one(path, target):
    """The summary rows of one shot (one per curve), or one row with the error."""
    try:
        m = sweepmtf.measure(path, target=target)
    except (sweepmtf.MeasurementError, OSError, ValueError) as e:
        return [dict.fromkeys(COLUMNS, "") | {"shot": path, "error": str(e)}]
    return [
        {
            "shot": path,
            "channel": c.channel,
            "sweep": c.sweep_id,
            "mtf50_cy_px": c.mtf50,
            "mtf30_cy_px": c.mtf30,
            "mtf10_cy_px": c.mtf10,
            "mtf_nyquist": c.mtf_nyquist,
            "chart_modulation": c.chart_modulation,
            "warnings": " | ".join(m.warnings),
            "error": "",
        }
        for c in m.curves
    ]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--target", required=True, help="target description (chart TOML)")
    ap.add_argument("-o", "--out", default="summary.csv", help="summary table (CSV)")
    ap.add_argument("--scheduler", default="processes", choices=["processes", "threads", "sync"])
    ap.add_argument("--partitions", type=int, default=os.cpu_count() or 1)
    a = ap.parse_args()
    shots = sorted(
        os.path.join(a.folder, f)
        for f in os.listdir(a.folder)
        if os.path.splitext(f)[1].lower() in PHOTO_EXTS
    )
    if not shots:
        sys.exit(f"{a.folder}: no photos (JPEG, PNG, TIFF, raw) found")
    bag = db.from_sequence(shots, npartitions=min(a.partitions, len(shots)))
    rows = bag.map(measure_one, a.target).flatten().compute(scheduler=a.scheduler)
    tmp = a.out + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(sorted(rows, key=lambda r: r["shot"]))
    os.replace(tmp, a.out)
    failed = sum(1 for r in rows if r["error"])
    print(f"{len(shots)} shots, {failed} failed -> {a.out}")


if __name__ == "__main__":
    main()
