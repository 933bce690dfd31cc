"""Choosing the manipulation model by name or by checkpoint path.

``--model`` (CLI) and ``model=`` (``lamp.solve``) take the same values everywhere:

- ``"learned"``: the trained checkpoint shipped in the package;
- ``"geometric"``: the hand-made contact strategies (``lamp.manip.GeometricProposer``);
- a path to a checkpoint written by ``lamp model train`` (``RUN_DIR/model.pt`` or its
  ``--export`` file).

:func:`check_model` resolves a value before any planning: it returns the canonical
spelling (a name, or an absolute path) or raises :class:`ModelError` naming the value and
what is wrong (unknown name, missing file, not a lamp checkpoint).
"""

from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any

from lamp.errors import InputError
from lamp.scene.errors import SceneError
from lamp.scene.model import Scene

#: The model names; anything else is read as a checkpoint path.
MODEL_NAMES = ("learned", "geometric")


class ModelError(InputError):
    """A ``--model`` value is neither a model name nor a usable checkpoint file."""


def _looks_like_path(value: str) -> bool:
    return any(c in value for c in "/\\.") or Path(value).exists()


def check_model(value: str | Path) -> str:
    """The canonical form of a model value: a name of ``MODEL_NAMES`` or an absolute path.

    A path must be an existing file that loads as a lamp checkpoint (it is opened here, so
    a bad file fails before any planning). Raises :class:`ModelError` otherwise.
    """
    text = str(value)
    if text in MODEL_NAMES:
        return text
    if not _looks_like_path(text):
        hint = difflib.get_close_matches(text, MODEL_NAMES, n=1)
        did = f"; did you mean {hint[0]!r}?" if hint else ""
        raise ModelError(f"unknown model {text!r}: expected {' or '.join(MODEL_NAMES)}, or a "
                         f"checkpoint file from `lamp model train`{did}")
    path = Path(text).expanduser()
    if not path.exists():
        raise ModelError(f"{text}: no such checkpoint file")
    if not path.is_file():
        raise ModelError(f"{text}: is not a file (a checkpoint is RUN_DIR/model.pt or the "
                         "--export file of `lamp model train`)")
    _load_checkpoint(path, threads=None)
    return str(path.resolve())


def _load_checkpoint(path: Path, threads: int | None) -> Any:
    from lamp.manip.network import load_model

    try:
        return load_model(path, threads=threads)
    except ValueError as exc:  # wrong format tag
        raise ModelError(str(exc)) from None
    except Exception as exc:  # noqa: BLE001 - unpickling errors, truncated files, bad keys
        raise ModelError(f"{path}: not a usable lamp checkpoint ({type(exc).__name__}: "
                         f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None


def load_proposer(model: str | Path | Any = "learned") -> Any:
    """The manipulation model for ``model`` (a name, a checkpoint path, or a model object)."""
    if not isinstance(model, (str, Path)):
        return model
    text = str(model)
    import lamp.manip as manip

    if text == "learned":
        return manip.load_model()
    if text == "geometric":
        return manip.GeometricProposer()
    if not _looks_like_path(text):
        check_model(text)  # raises with the list of names
    path = Path(text).expanduser()
    if not path.is_file():
        raise ModelError(f"{text}: no such checkpoint file")
    return _load_checkpoint(path, threads=1)


def model_robot_radius(model: str | Path | Any = "learned") -> float | None:
    """The robot radius (m) the model makes contacts for; None when it serves any.

    The shipped model's is read from its metadata (``flow_dc.json``) without loading
    PyTorch, so that ``lamp validate`` stays quick.
    """
    if str(model) == "learned" and isinstance(model, (str, Path)):
        import json
        from importlib.resources import files

        from lamp.manip.contacts import ROBOT_RADIUS

        meta = json.loads((files("lamp.manip") / "checkpoints" / "flow_dc.json").read_text())
        return float(meta.get("data_meta", {}).get("robot_radius", ROBOT_RADIUS))
    want = getattr(load_proposer(model), "robot_radius", None)
    return None if want is None else float(want)


def check_robot_radius(scene: Scene, proposer: Any) -> None:
    """Refuse a scene whose robots the manipulation model does not make contacts for
    (``proposer``: the model, or the radius it serves; None serves any).

    The model's contacts sit ``robot_radius`` (plus a gap) off the object, so robots of
    another size would fail every ``Collide`` check or touch the object before the push:
    a :class:`~lamp.scene.SceneError` naming ``robots.radius`` instead of a run that
    silently finds nothing.
    """
    want = (proposer if isinstance(proposer, (int, float)) or proposer is None
            else getattr(proposer, "robot_radius", None))
    if want is not None and abs(float(scene.robot_radius) - float(want)) > 1e-9:
        where = scene.source or scene.name
        reason = (f"the manipulation model makes contacts for robots of radius "
                  f"{float(want):g} m, got {float(scene.robot_radius):g}; use robots of radius "
                  f"{float(want):g} m (or train a model for yours: lamp model data/train)")
        raise SceneError(f"{where}: robots.radius: {reason}", path=scene.source,
                         field="robots.radius", reason=reason)
