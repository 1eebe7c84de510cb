"""Suites: TOML files → the grid of cells (the first step of a leaderboard run).

* A **suite** is a small TOML file (``crowdbench/leaderboard/suites/*.toml``: ``paper`` — Tables I–IV, 500 episodes
  per cell, the published seed; ``quick`` — minutes, for trying a new policy; ``shift`` — Table V) or any path;
  :func:`load_suite` validates it.
* Its **grid** is the list of :class:`Cell` settings of its tables (:func:`grid`), optionally a subset of rows:

  * Table I — circle crossing, 20 pedestrians, ρ ∈ {0.7 High, 0.5 Medium, 0.3 Low};
  * Table II — circle crossing, ρ = 0 (non-responsive regime), N ∈ {10, 20, 30};
  * Table III — unseen layouts (intersection, split flow, random wander), 30 pedestrians, ρ ∈ {0.7, 0.5, 0.3};
  * Table IV — real crowds: the five ETH/UCY scenes, recorded people replayed blind to the robot (``replay``) or
    avoiding it and rejoining their paths (``reactive_replay``), slots for the scene's peak crowd;
  * Table V — crowd-model shift: circle crossing, 20 pedestrians of each model of :data:`SHIFT_MODELS` (every
    method was trained among latent-responsive ORCA pedestrians).

Each cell uses evaluation seed S (episode k ↔ world seed S + k), so every policy meets exactly the same crowds.
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from crowdbench.validate import check_fields

SUITES_DIR = Path(__file__).resolve().parent / "suites"
"""The shipped suites (``--suite NAME``)."""

REGIMES = {"High": 0.7, "Medium": 0.5, "Low": 0.3}


TABLES = ("I", "II", "III", "IV", "V")
SHIFT_MODELS = ("responsive_orca", "orca", "social_force", "learned_crowd")
"""Table V's crowds: the training crowd (latent-responsive ORCA, ρ = 0.5) and three others."""

@dataclass(frozen=True)
class Cell:
    """One evaluation setting: table, row label, layout, crowd size, mean responsiveness ρ and pedestrian model."""

    table: str
    row: str
    layout: str
    humans: int
    rho: float
    model: str = "responsive_orca"


def grid(tables: tuple[str, ...] = ("I", "II", "III")) -> list[Cell]:
    """The grid of the requested tables."""
    from crowdbench.worlds.recorded import PEAK

    out: list[Cell] = []
    if "I" in tables:
        out += [Cell("I", name, "circle_crossing", 20, rho) for name, rho in REGIMES.items()]
    if "II" in tables:
        out += [Cell("II", f"N={n}", "circle_crossing", n, 0.0) for n in (10, 20, 30)]
    if "III" in tables:
        out += [Cell("III", f"{lay} {name}", lay, 30, rho) for lay in ("intersection", "split_flow", "random_wander")
                for name, rho in REGIMES.items()]
    if "V" in tables:
        out += [Cell("V", m if m != "responsive_orca" else "responsive_orca ρ=0.5", "circle_crossing", 20,
                     0.5 if m == "responsive_orca" else 0.0, m) for m in SHIFT_MODELS]
    if "IV" in tables:
        out += [Cell("IV", f"{scene} {model}", scene, peak, 0.0, model) for scene, peak in PEAK.items()
                for model in ("replay", "reactive_replay")]
    return out


@dataclass(frozen=True)
class Suite:
    """An evaluation suite (a TOML file in :data:`SUITES_DIR`, or any path); its fingerprint part is
    :func:`crowdbench.leaderboard.cells.suite_digest`."""

    name: str
    """Short name (the file's stem for shipped suites)."""
    description: str = ""
    episodes: int = 500
    """Episodes per cell."""
    seed: int = 0
    """Evaluation seed: episode k of every cell runs world seed ``seed + k``."""
    check_seed: int | None = None
    """A second, disjoint evaluation seed range: every cell is evaluated there too and stored beside its result
    (``check``), out of sample — the two must agree within their intervals (``crowdbench leaderboard paper``
    reports where they do not). None: no check."""
    tables: tuple[str, ...] = ("I", "II", "III")
    """Which tables (their cells: :func:`grid`): the paper's I–III and IV, real crowds."""
    rows: tuple[str, ...] = ()
    """Optional subset of the tables' cells by ``TABLE/ROW`` (e.g. ``"III/split_flow Medium"``); empty = all."""
    worlds: int = 100
    """Worlds stepped together per cell."""
    counterfactual: bool = True
    """Run the robot-absent twin for the pedestrians' delay (doubles the crowd simulation)."""

    def __post_init__(self) -> None:
        check_fields(self)
        if not self.name:
            raise ValueError(f"suite name={self.name!r}; valid choices: a non-empty string")
        for key in ("episodes", "worlds"):
            if not isinstance(getattr(self, key), int) or getattr(self, key) < 1:
                raise ValueError(f"suite {self.name!r}: {key}={getattr(self, key)!r}; valid choices: an integer ≥ 1")
        if not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"suite {self.name!r}: seed={self.seed!r}; valid choices: an integer ≥ 0")
        if self.check_seed is not None and (not isinstance(self.check_seed, int)
                                            or abs(self.check_seed - self.seed) < self.episodes):
            raise ValueError(f"suite {self.name!r}: check_seed={self.check_seed!r}; valid choices: None or an integer "
                             f"at least episodes={self.episodes} away from seed={self.seed} (disjoint world seeds)")
        object.__setattr__(self, "tables", tuple(self.tables))
        object.__setattr__(self, "rows", tuple(self.rows))
        bad = [t for t in self.tables if t not in TABLES]
        if bad or not self.tables:
            raise ValueError(f"suite {self.name!r}: tables={list(self.tables)}; valid choices: a non-empty subset of "
                             f"{', '.join(TABLES)}")
        known = {f"{c.table}/{c.row}" for c in grid(self.tables)}
        unknown = sorted(set(self.rows) - known)
        if unknown:
            raise ValueError(f"suite {self.name!r}: rows {unknown} are not cells of tables {list(self.tables)}; "
                             f"valid choices: {', '.join(sorted(known))}")

    def grid(self) -> list[Cell]:
        """The suite's cells: its tables' (:func:`grid`), limited to :attr:`rows` when given."""
        return [c for c in grid(self.tables) if not self.rows or f"{c.table}/{c.row}" in self.rows]

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["tables"], d["rows"] = list(self.tables), list(self.rows)
        return d



def suite_names() -> list[str]:
    return sorted(p.stem for p in SUITES_DIR.glob("*.toml"))


def load_suite(name_or_path: str, **overrides: Any) -> Suite:
    """A shipped suite by name or a TOML file by path; ``overrides`` (e.g. ``episodes=50``) replace its fields.
    Unknown keys and bad values are one clear error."""
    path = Path(name_or_path)
    if not path.suffix:
        path = SUITES_DIR / f"{name_or_path}.toml"
        if not path.exists():
            raise ValueError(f"--suite {name_or_path!r}: no such suite; valid choices: {', '.join(suite_names())} "
                             "or a path to a .toml file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ValueError(f"--suite {str(path)!r}: file not found") from None
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"suite file {str(path)!r} is not valid TOML: {e}") from None
    data.setdefault("name", path.stem)
    data.update({k: v for k, v in overrides.items() if v is not None})
    fields = {f.name for f in dataclasses.fields(Suite)}
    unknown = sorted(set(data) - fields)
    if unknown:
        raise ValueError(f"suite {str(path)!r}: unknown keys {unknown}; valid choices: {', '.join(sorted(fields))}")
    return Suite(**data)

