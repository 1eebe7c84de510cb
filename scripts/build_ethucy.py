"""Build ``crowdbench/datasets/data/ethucy.npz`` from the raw ETH/UCY files of Trajectron++.

    python scripts/build_ethucy.py RAW [--out crowdbench/datasets/data/ethucy.npz]

``RAW`` is ``experiments/pedestrians/raw`` of StanfordASL/Trajectron-plus-plus (its ``raw/all_data``, ``raw/train``
and ``raw/val`` folders are read). Each recording is stored whole, float64 (frame, pedestrian id, x, y), with the
number of its leading rows that form its train split (the rest is its validation split); the build checks that every
stored array equals the parsed raw files exactly and that train + val is the whole recording.
"""

from __future__ import annotations

import argparse
import io
import os

import numpy as np

from crowdbench.datasets.ethucy import RECORDINGS


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("raw", help="Trajectron-plus-plus/experiments/pedestrians/raw")
    p.add_argument("--out", default=os.path.join("crowdbench", "datasets", "data", "ethucy.npz"))
    a = p.parse_args()
    arrays: dict[str, np.ndarray] = {}
    for name in RECORDINGS:
        full = np.loadtxt(os.path.join(a.raw, "raw", "all_data", f"{name}.txt"), dtype=np.float64, ndmin=2)
        train = np.loadtxt(os.path.join(a.raw, "raw", "train", f"{name}_train.txt"), dtype=np.float64, ndmin=2)
        val = np.loadtxt(os.path.join(a.raw, "raw", "val", f"{name}_val.txt"), dtype=np.float64, ndmin=2)
        k = len(train)
        if not (np.array_equal(full[:k], train) and np.array_equal(full[k:], val)):
            raise SystemExit(f"{name}: train + val is not the whole recording; the stored split would be wrong")
        arrays[name] = full
        arrays[f"{name}__train_rows"] = np.array(k, dtype=np.int64)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    tmp = a.out + ".tmp"
    with open(tmp, "wb") as f:
        f.write(buf.getvalue())
    os.replace(tmp, a.out)
    rows = sum(len(v) for v in arrays.values() if v.ndim)
    print(f"wrote {a.out} ({os.path.getsize(a.out) / 1e6:.2f} MB, {rows} rows)")


if __name__ == "__main__":
    main()
