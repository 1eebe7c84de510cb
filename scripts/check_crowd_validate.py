"""An independent reference for ``crowdbench crowd-validate --models const_vel``: plain Python on the raw files.

    python scripts/check_crowd_validate.py <Trajectron-plus-plus>/experiments/pedestrians/raw

Reads each scene's test files as text (no numpy, none of crowdbench's loader), slides 20-frame windows over the
distinct frames (Social GAN's loader), keeps the pedestrians present in all 20, extrapolates the last observed
velocity over 12 frames and prints ADE / FDE [m] and the sample count per scene, beside crowdbench's figures.
"""

from __future__ import annotations

import collections
import math
import os
import sys

SCENES = {"eth": ["eth/test/biwi_eth.txt"], "hotel": ["hotel/test/biwi_hotel.txt"],
          "univ": ["univ/test/students001.txt", "univ/test/students003.txt"],
          "zara1": ["zara1/test/crowds_zara01.txt"], "zara2": ["zara2/test/crowds_zara02.txt"]}


def reference(raw: str, files: list[str]) -> tuple[float, float, int]:
    ade = fde = 0.0
    n = 0
    for name in files:
        by_frame: dict[float, dict[float, tuple[float, float]]] = collections.defaultdict(dict)
        with open(os.path.join(raw, name)) as f:
            for line in f:
                if line.strip():
                    fr, pid, x, y = map(float, line.split())
                    by_frame[fr][pid] = (x, y)
        frames = sorted(by_frame)
        for s in range(len(frames) - 19):
            window = frames[s:s + 20]
            people = set(by_frame[window[0]]).intersection(*(by_frame[fr] for fr in window[1:]))
            for p in people:
                tr = [by_frame[fr][p] for fr in window]
                vx, vy = tr[7][0] - tr[6][0], tr[7][1] - tr[6][1]
                err = [math.hypot(tr[7][0] + k * vx - tr[7 + k][0], tr[7][1] + k * vy - tr[7 + k][1])
                       for k in range(1, 13)]
                ade, fde, n = ade + sum(err) / 12, fde + err[-1], n + 1
    return ade / n, fde / n, n


def main() -> None:
    from crowdbench.datasets.validate import validate

    ours = validate(["const_vel"])
    for scene, files in SCENES.items():
        ade, fde, n = reference(sys.argv[1], files)
        o = ours[scene]["const_vel"]
        print(f"{scene:>6}: reference {ade:.4f} / {fde:.4f} ({n} samples) — crowdbench {o['ade']:.4f} / "
              f"{o['fde']:.4f} ({o['samples']})")


if __name__ == "__main__":
    main()
