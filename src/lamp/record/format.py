"""The recording format ``lamp-recording/1``: a run's trajectories and events, numpy-only.

A recording is two files in a run folder (see ``docs/recording-format.md``):

- ``recording.npz``: the arrays of :data:`ARRAYS` (``np.savez_compressed``, no pickles);
- ``recording.json``: the index: ``format``, the scene (a ``lamp-scene/1`` dict), planner,
  seed, the run's ``result.json`` object, the sampling interval, the outcome names and the
  dtype and shape of every array.

Trajectories are sampled every ``row_dt_s`` simulated seconds (0.08 s: the time of one
0.02 m waypoint row at robot speed), plus the last state of every segment. Segment ``g``
covers rows ``segment_rows[g]`` to ``segment_rows[g + 1]`` inclusive: its first row is the
state it started from. Ragged per-segment and per-plan data (contacts, pushes, planned
paths, edges) are flat arrays cut by ``*_offsets`` arrays of length count + 1.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from lamp.errors import InputError

#: The format name written to and required in ``recording.json``.
FORMAT = "lamp-recording/1"
NPZ_NAME = "recording.npz"
JSON_NAME = "recording.json"

#: What the loop did after a segment (``segment_outcome`` holds the index into this tuple).
OUTCOMES = ("continue", "drift", "stalled", "left", "team")

# name -> (dtype, shape with symbolic sizes): S rows, N robots, K objects, G segments,
# C contacts, M push points, L plans, P planned poses, E / F verified / penalised edges
ARRAYS: dict[str, tuple[str, tuple[str | int, ...]]] = {
    "times": ("float64", ("S",)),
    "robots": ("float32", ("S", "N", 2)),
    "objects": ("float32", ("S", "K", 3)),
    "segment_rows": ("int64", ("G+1",)),
    "segment_object": ("int32", ("G",)),
    "segment_plan": ("int32", ("G",)),
    "segment_outcome": ("int8", ("G",)),
    "segment_replanned": ("bool", ("G",)),
    "planning_time_s": ("float64", ("G",)),
    "sim_time_s": ("float64", ("G",)),
    "drift": ("float32", ("G", 2)),
    "planned_from": ("float32", ("G", 3)),
    "planned_to": ("float32", ("G", 3)),
    "contact_offsets": ("int64", ("G+1",)),
    "contacts": ("float32", ("C", 2)),
    "push_offsets": ("int64", ("C+1",)),
    "pushes": ("float32", ("M", 2)),
    "plan_object": ("int32", ("L",)),
    "plan_path_offsets": ("int64", ("L+1",)),
    "plan_path": ("float32", ("P", 3)),
    "verified_offsets": ("int64", ("L+1",)),
    "verified": ("float32", ("E", 2, 2)),
    "penalised_offsets": ("int64", ("L+1",)),
    "penalised": ("float32", ("F", 2, 2)),
}

#: Arrays a recording may hold (same conventions): ``robot_team[s, i]`` is the object
#: robot ``i`` works for at row ``s`` (-1: none), written by the concurrent schedule.
OPTIONAL_ARRAYS: dict[str, tuple[str, tuple[str | int, ...]]] = {
    "robot_team": ("int16", ("S", "N")),
}

#: Which offsets array cuts which flat array, and the count its length is one more than.
RAGGED = {
    "contacts": ("contact_offsets", "G"),
    "pushes": ("push_offsets", "C"),
    "plan_path": ("plan_path_offsets", "L"),
    "verified": ("verified_offsets", "L"),
    "penalised": ("penalised_offsets", "L"),
}


class RecordingError(InputError):
    """A recording that cannot be read: the message names the file and the field."""


@dataclass(frozen=True)
class Recording:
    """A recorded run: the scene, who ran it, its result and the arrays of :data:`ARRAYS`.

    Construction checks every array's dtype and shape against :data:`ARRAYS` and that the
    offsets arrays cut their flat arrays exactly (RecordingError otherwise), so accessors
    never index out of range; ``arrays`` is then a read-only mapping of read-only copies.
    """

    scene: dict[str, Any]
    planner: str
    seed: int
    result: dict[str, Any]
    row_dt_s: float
    arrays: Mapping[str, np.ndarray] = field(repr=False)

    def __post_init__(self) -> None:
        check_arrays(self.arrays, where="arrays")
        frozen = {}
        for name in [*ARRAYS, *(k for k in OPTIONAL_ARRAYS if k in self.arrays)]:
            arr = np.array(self.arrays[name], copy=True)
            arr.flags.writeable = False
            frozen[name] = arr
        object.__setattr__(self, "arrays", MappingProxyType(frozen))

    # ---------------------------------------------------------------- sizes
    @property
    def n_rows(self) -> int:
        return len(self.arrays["times"])

    @property
    def n_segments(self) -> int:
        return len(self.arrays["segment_object"])

    @property
    def success(self) -> bool:
        return bool(self.result.get("success", False))

    def scene_model(self):
        """The recorded scene as a :class:`lamp.scene.Scene`."""
        from lamp.scene import scene_from_dict

        return scene_from_dict(self.scene, source="recording.json")

    # --------------------------------------------------------------- ragged
    def _cut(self, name: str, i: int) -> np.ndarray:
        offsets = self.arrays[RAGGED[name][0]]
        return self.arrays[name][offsets[i] : offsets[i + 1]]

    def segment_of_row(self, row: int) -> int:
        """The segment drawn with row ``row``: the one whose rows (start, end] hold it (row
        0: segment 0), so a segment's last row shows that segment; -1 with no segments."""
        rows = self.arrays["segment_rows"]
        if self.n_segments == 0:
            return -1
        g = int(np.searchsorted(rows, row, side="left")) - 1
        return min(max(g, 0), self.n_segments - 1)

    def contacts_of(self, segment: int) -> np.ndarray:
        """(B, 2) world contact points of ``segment``."""
        return self._cut("contacts", segment)

    def pushes_of(self, segment: int) -> list[np.ndarray]:
        """The world-frame push polyline (H, 2) of each contact of ``segment``."""
        offsets = self.arrays["contact_offsets"]
        return [self._cut("pushes", c) for c in range(offsets[segment], offsets[segment + 1])]

    def plan_path(self, plan: int) -> np.ndarray:
        """(P, 3) object path planned by plan ``plan`` (empty for -1, no plan)."""
        return np.zeros((0, 3), np.float32) if plan < 0 else self._cut("plan_path", plan)

    def verified_of(self, plan: int) -> np.ndarray:
        return np.zeros((0, 2, 2), np.float32) if plan < 0 else self._cut("verified", plan)

    def penalised_of(self, plan: int) -> np.ndarray:
        return np.zeros((0, 2, 2), np.float32) if plan < 0 else self._cut("penalised", plan)

    def index(self) -> dict[str, Any]:
        """The ``recording.json`` object."""
        return {
            "format": FORMAT,
            "planner": self.planner,
            "seed": int(self.seed),
            "row_dt_s": float(self.row_dt_s),
            "outcomes": list(OUTCOMES),
            "counts": {"rows": self.n_rows, "segments": self.n_segments,
                       "plans": len(self.arrays["plan_object"])},
            "arrays": {k: {"dtype": str(v.dtype), "shape": list(v.shape)}
                       for k, v in self.arrays.items()},
            "scene": self.scene,
            "result": self.result,
        }


def check_arrays(arrays: Mapping[str, Any], where: str) -> None:
    """RecordingError unless ``arrays`` holds exactly :data:`ARRAYS` (and any of
    :data:`OPTIONAL_ARRAYS`) with consistent sizes."""
    missing = [k for k in ARRAYS if k not in arrays]
    if missing:
        raise RecordingError(f"{where}: missing arrays {', '.join(missing)}")
    extra = [k for k in arrays if k not in ARRAYS and k not in OPTIONAL_ARRAYS]
    if extra:
        raise RecordingError(f"{where}: unknown arrays {', '.join(extra)}")
    sizes: dict[str, int] = {}
    present = {**ARRAYS, **{k: v for k, v in OPTIONAL_ARRAYS.items() if k in arrays}}
    for name, (dtype, shape) in present.items():
        arr = arrays[name]
        if not isinstance(arr, np.ndarray) or arr.dtype != np.dtype(dtype):
            got = getattr(arr, "dtype", type(arr).__name__)
            raise RecordingError(f"{where}.{name}: expected dtype {dtype}, got {got}")
        if arr.ndim != len(shape):
            raise RecordingError(f"{where}.{name}: expected {len(shape)} dimensions "
                                 f"{shape}, got shape {arr.shape}")
        for dim, want in zip(arr.shape, shape, strict=True):
            if isinstance(want, int):
                ok = dim == want
            else:
                sym, plus = (want[:-2], 1) if want.endswith("+1") else (want, 0)
                ok = sizes.setdefault(sym, dim - plus) == dim - plus
            if not ok:
                raise RecordingError(f"{where}.{name}: shape {arr.shape} does not match "
                                     f"{shape} with sizes {sizes}")
    for name, (off_name, _) in RAGGED.items():
        off = arrays[off_name]
        if off[0] != 0 or off[-1] != len(arrays[name]) or np.any(np.diff(off) < 0):
            raise RecordingError(f"{where}.{off_name}: must rise from 0 to "
                                 f"{len(arrays[name])} (the length of {name})")
    rows = arrays["segment_rows"]
    n_rows = len(arrays["times"])
    if rows[0] != 0 or np.any(np.diff(rows) < 0) or rows[-1] > max(n_rows - 1, 0):
        raise RecordingError(f"{where}.segment_rows: must rise from 0 to at most "
                             f"{n_rows - 1} (the last row)")
    plans = arrays["segment_plan"]
    if np.any((plans < -1) | (plans >= len(arrays["plan_object"]))):
        raise RecordingError(f"{where}.segment_plan: indices must be -1 or name a plan")
    if np.any((arrays["segment_outcome"] < 0) | (arrays["segment_outcome"] >= len(OUTCOMES))):
        raise RecordingError(f"{where}.segment_outcome: values must index {OUTCOMES}")


def save_recording(recording: Recording, run_dir: str | Path) -> tuple[Path, Path]:
    """Write ``recording.npz`` and ``recording.json`` into ``run_dir``, each atomically (the
    npz first, so a complete index always describes a complete array file)."""
    from lamp.io import atomic_output, write_json_atomic

    run_dir = Path(run_dir)
    npz, index = run_dir / NPZ_NAME, run_dir / JSON_NAME
    with atomic_output(npz, keep_suffix=True) as tmp, open(tmp, "wb") as f:
        np.savez_compressed(f, **dict(recording.arrays))
    write_json_atomic(index, recording.index())
    return npz, index


def load_recording(run_dir: str | Path) -> Recording:
    """Read the recording of a run folder (or of a ``recording.json`` path).

    Raises RecordingError naming the file and field for a missing or malformed recording.
    """
    path = Path(run_dir)
    index_path = path if path.suffix == ".json" else path / JSON_NAME
    npz_path = index_path.with_name(NPZ_NAME)
    if not index_path.is_file():
        raise RecordingError(f"{index_path}: no recording here (run `lamp run` first)")
    try:
        index = json.loads(index_path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise RecordingError(f"{index_path}: not a JSON file: {exc}") from None
    if not isinstance(index, dict) or index.get("format") != FORMAT:
        got = index.get("format") if isinstance(index, dict) else type(index).__name__
        raise RecordingError(f"{index_path}: format: expected {FORMAT!r}, got {got!r}")
    for key, kind in (("scene", dict), ("planner", str), ("seed", int), ("result", dict),
                      ("row_dt_s", (int, float))):
        if not isinstance(index.get(key), kind):
            raise RecordingError(f"{index_path}: {key}: missing or of the wrong type "
                                 f"({index.get(key)!r})")
    from lamp.scene import SceneError, scene_from_dict

    try:
        scene_from_dict(index["scene"], source=str(index_path))
    except SceneError as exc:
        raise RecordingError(f"{index_path}: scene: {exc}") from None
    if not npz_path.is_file():
        raise RecordingError(f"{npz_path}: missing (the index {index_path} refers to it)")
    try:
        with np.load(npz_path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError) as exc:
        raise RecordingError(f"{npz_path}: not a readable npz file: {exc}") from None
    try:
        return Recording(index["scene"], index["planner"], index["seed"], index["result"],
                         float(index["row_dt_s"]), arrays)
    except RecordingError as exc:
        raise RecordingError(f"{npz_path}: {exc}") from None
