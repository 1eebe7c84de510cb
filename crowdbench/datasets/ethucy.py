"""The five ETH/UCY scenes — ETH, Hotel (Pellegrini et al., ICCV 2009) and Univ, Zara1, Zara2 (Lerner et al.,
Eurographics 2007) — in world coordinates [m], one frame every 0.4 s, as distributed with Trajectron++
(StanfordASL/Trajectron-plus-plus, ``experiments/pedestrians/raw``; see ``data/ETHUCY.md`` for source, citation and
the recordings' licence note).

Each of the eight recordings is package data (``data/ethucy.npz``, built by ``scripts/build_ethucy.py`` and checked
equal to the raw files): rows ``(frame, pedestrian id, x, y)`` in file order, and how many leading rows form its
train split (the rest is its validation split). The usual leave-one-scene-out protocol: a scene's **test** split is
its own recordings, whole (``univ``: ``students001`` and ``students003``); its **train** and **val** splits are the
train and validation parts of every *other* recording (``crowds_zara03`` and ``uni_examples`` are train/val data
only).
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data" / "ethucy.npz"
RECORDINGS = ("biwi_eth", "biwi_hotel", "crowds_zara01", "crowds_zara02", "crowds_zara03", "students001",
              "students003", "uni_examples")
"""The recordings, by their file names in the raw data."""
SCENES = {"eth": ("biwi_eth",), "hotel": ("biwi_hotel",), "univ": ("students001", "students003"),
          "zara1": ("crowds_zara01",), "zara2": ("crowds_zara02",)}
"""Each scene's test recordings."""
SPLITS = ("train", "val", "test")
FRAME_STEP = 10
"""Frame numbers advance by 10 per annotated frame [frames]."""
DT = 0.4
"""Time between annotated frames [s]."""


@functools.cache
def _archive() -> dict[str, np.ndarray]:
    with np.load(DATA) as z:
        return {k: z[k] for k in z.files}


def load_recording(name: str, part: str = "all") -> np.ndarray:
    """Rows ``(n, 4)`` = (frame, pedestrian id, x [m], y [m]) of one recording, float64, in file order; ``part``:
    ``all``, ``train`` or ``val``."""
    if name not in RECORDINGS:
        raise ValueError(f"recording={name!r}; valid choices: {', '.join(RECORDINGS)}")
    arc = _archive()
    rows, k = arc[name], int(arc[f"{name}__train_rows"])
    if part == "all":
        return rows.copy()
    if part == "train":
        return rows[:k].copy()
    if part == "val":
        return rows[k:].copy()
    raise ValueError(f"part={part!r}; valid choices: all, train, val")


def scene_recordings(scene: str, split: str = "test") -> list[tuple[str, np.ndarray]]:
    """``(recording, rows)`` of one scene's split (module docstring: leave one scene out)."""
    if scene not in SCENES:
        raise ValueError(f"scene={scene!r}; valid choices: {', '.join(SCENES)}")
    if split not in SPLITS:
        raise ValueError(f"split={split!r}; valid choices: {', '.join(SPLITS)}")
    if split == "test":
        return [(name, load_recording(name)) for name in SCENES[scene]]
    return [(name, load_recording(name, split)) for name in RECORDINGS if name not in SCENES[scene]]


def tracks(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A recording as a dense grid: ``frames`` ``(T,)`` (its distinct frame numbers, sorted), ``ids`` ``(P,)`` and
    ``pos`` ``(T, P, 2)`` [m], NaN where pedestrian p is not annotated in frame t."""
    frames, t = np.unique(rows[:, 0], return_inverse=True)
    ids, p = np.unique(rows[:, 1], return_inverse=True)
    pos = np.full((len(frames), len(ids), 2), np.nan)
    pos[t, p] = rows[:, 2:4]
    return frames, ids, pos
