"""The ``lamp`` command line as a user meets it: options, help, errors, progress, exit codes.

Everything goes through typer's ``CliRunner`` (or a subprocess where a fresh process is the
point: the Numba compile cache). Runs use small scenes and the geometric model.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import typer
from typer.testing import CliRunner

import lamp
from lamp.cli import app
from lamp.pipeline.registry import default_planning_limit, descriptions

DATA = Path(__file__).parent / "data"
SPEC = DATA / "spec_example.yaml"
runner = CliRunner()
WIDE = {"COLUMNS": "240", "NO_COLOR": "1"}


def small_scene(goal=(1.15, 1.0, 0.0)) -> dict:
    return {
        "format": "lamp-scene/1", "name": "small", "workspace": [2.2, 2.0],
        "robots": {"radius": 0.05, "starts": [[0.2, 0.3], [0.2, 0.6], [0.2, 0.9]]},
        "objects": [{"type": "rectangle", "size": [0.3, 0.2], "start": [0.85, 1.0, 0.0],
                     "goal": list(goal)}],
    }


@pytest.fixture
def small(tmp_path: Path) -> Path:
    path = tmp_path / "small.yaml"
    path.write_text(json.dumps(small_scene()))
    return path


@pytest.fixture
def no_planning(monkeypatch: pytest.MonkeyPatch):
    """Make any attempt to plan fail the test: input checks must come first."""
    from lamp.pipeline import execute as execute_mod

    def boom(*a, **k):
        raise AssertionError("planning started before the input was checked")

    monkeypatch.setattr(execute_mod, "object_runner", boom)


def help_text(*args: str) -> str:
    res = runner.invoke(app, [*args, "--help"], env=WIDE)
    assert res.exit_code == 0, res.output
    return res.output


# --------------------------------------------------------------------------- global options


def test_version_and_short_help() -> None:
    for flag in ("--version", "-V"):
        res = runner.invoke(app, [flag])
        assert res.exit_code == 0
        assert res.output.strip() == f"lamp {lamp.__version__}"
    assert "Usage: lamp" in runner.invoke(app, ["-h"], prog_name="lamp").output
    for cmd in (["run"], ["bench"], ["model", "data"], ["suite", "export"], ["validate"]):
        res = runner.invoke(app, [*cmd, "-h"])
        assert res.exit_code == 0 and "Usage:" in res.output, (cmd, res.output)


def test_shell_completion_is_available() -> None:
    """In a fresh process with the shell named (in process, Typer's shell detection made
    this test depend on what ran before it and on the parent shell)."""
    assert "--install-completion" in help_text()
    lamp_exe = Path(sys.executable).with_name("lamp")
    # with shell detection on, Typer's --show-completion is a flag and asks shellingham
    # which shell started the process (none under make or CI); this switch makes it take
    # the shell named on the command line
    env = {**os.environ, "_TYPER_COMPLETE_TEST_DISABLE_SHELL_DETECTION": "1"}
    res = subprocess.run([str(lamp_exe), "--show-completion", "bash"], capture_output=True,
                         text=True, timeout=300, env=env)
    assert res.returncode == 0, res.stderr
    assert "complete" in res.stdout and "_LAMP_COMPLETE" in res.stdout, res.stdout


def _visible_options(cmd: Any, path: str = "lamp"):
    """``(command path, option)`` for every option ``--help`` shows, in every command.
    Duck-typed: Typer may bring its own copy of Click, whose classes are not ``click``'s."""
    commands = getattr(cmd, "commands", None)
    if commands is not None:
        for name, sub in commands.items():
            yield from _visible_options(sub, f"{path} {name}")
        return
    for p in cmd.params:
        if p.param_type_name == "option" and not p.hidden:
            yield path, p


def test_the_option_walk_sees_every_command() -> None:
    paths = {path for path, _ in _visible_options(typer.main.get_command(app))}
    assert {"lamp run", "lamp bench", "lamp model eval", "lamp suite fleet-scene"} <= paths


def test_every_option_shows_its_default() -> None:
    """An option without a value of its own says in --help what happens when it is left out
    (a ``show_default`` text, or its help saying what the default is)."""
    missing = [f"{path} {p.opts[0]}" for path, p in _visible_options(typer.main.get_command(app))
               if not p.is_flag and not p.required and p.name != "help"
               and p.show_default is not False
               and p.default is None and not isinstance(p.show_default, str)
               and not re.search(r"default|when not given", p.help or "")]
    assert missing == []


def test_one_spelling_per_idea_old_ones_hidden() -> None:
    run_help, bench_help = help_text("run"), help_text("bench")
    assert "--planning-limit" in run_help and "--planning-limit" in bench_help
    for name in descriptions():  # the per-planner defaults are shown
        assert f"{default_planning_limit(name):g} s" in run_help
    assert "--time-limit" not in run_help and "--time-limit" not in bench_help
    assert "--suites" in bench_help and "--num-seeds" in bench_help
    assert not re.search(r"(?<![\w-])--(suite|seeds)\b(?!-)", bench_help)
    assert "-j" in help_text("model", "data") and "-j" in bench_help
    eval_help = help_text("model", "eval")
    assert "--proposals" in eval_help and not re.search(r"--k\b", eval_help)


#: Long options that mean different things in different commands, kept because both
#: meanings are documented: ``lamp render --size`` (pixels), ``lamp suite fleet-scene
#: --size`` (the map's width and height in metres).
SAME_NAME_OTHER_MEANING = {"--size"}


def test_an_option_means_the_same_in_every_command() -> None:
    """A short option stands for one long option everywhere; each of the shared ideas has
    its one spelling (a seed is ``-s/--seed``, an output ``-o/--out``, ``-q/--quiet`` prints
    nothing but errors); a visible ``--record`` is ``lamp bench``'s alone."""
    options = list(_visible_options(typer.main.get_command(app)))
    longs_of_short: dict[str, set[str]] = {}
    for _, p in options:  # --planner and --planners (lamp bench) are one idea
        longs = {o.removesuffix("s") for o in p.opts if o.startswith("--")}
        for short in (o for o in p.opts if not o.startswith("--")):
            longs_of_short.setdefault(short, set()).update(longs)
    assert {s: ls for s, ls in longs_of_short.items() if len(ls) > 1} == {}
    for long, short in (("--seed", "-s"), ("--out", "-o"), ("--model", "-m"),
                        ("--workers", "-j"), ("--quiet", "-q"), ("--planner", "-p"),
                        ("--planners", "-p")):
        missing = [path for path, p in options if long in p.opts and short not in p.opts]
        assert missing == [], f"{long} without {short} in {missing}"
    quiet = {path for path, p in options if "--quiet" in p.opts}
    assert quiet == {"lamp run", "lamp demo", "lamp bench"}
    assert {path for path, p in options if "--record" in p.opts} == {"lamp bench"}
    meanings: dict[str, set[str]] = {}
    for _, p in options:
        for long in (o for o in p.opts if o.startswith("--")):
            meanings.setdefault(long, set()).add(p.name)
    assert {o for o, names in meanings.items() if len(names) > 1} <= SAME_NAME_OTHER_MEANING


def test_old_spellings_still_work(small: Path, no_planning) -> None:
    res = runner.invoke(app, ["run", str(small), "--time-limit", "-1"])
    assert res.exit_code == 2 and "--planning-limit: must be positive" in res.stderr
    res = runner.invoke(app, ["model", "eval", "--k", "0"])
    assert res.exit_code == 2 and "--proposals" in res.stderr
    for flag in ("--record", "--no-record", "--store-in-checkpoint"):  # checked before running
        res = runner.invoke(app, ["model", "eval", flag, "--proposals", "0"])
        assert res.exit_code == 2 and "--proposals" in res.stderr, res.output
    res = runner.invoke(app, ["bench", "--suite", "iros", "--time-limit", "-1", "--out",
                              str(small.parent / "b"), "--dry-run"])
    assert res.exit_code == 2 and "--planning-limit must be positive" in res.stderr
    res = runner.invoke(app, ["bench", "--suite", "iros", "--seeds", "3", "--out",
                              str(small.parent / "b"), "--dry-run"])
    assert res.exit_code == 0 and "x 3 seeds" in res.output


def test_units_in_help_survive_rich_markup() -> None:
    text = help_text("model", "data")
    assert "[m]" in text and "[rad]" in text


def test_planner_choices_listed_and_suggested(small: Path, no_planning, tmp_path: Path) -> None:
    text = help_text("run")
    for name in descriptions():
        assert name in text
    res = runner.invoke(app, ["run", str(small), "-p", "lazzy", "-o", str(tmp_path / "o")])
    assert res.exit_code == 2
    assert "unknown planner 'lazzy'" in res.stderr and "did you mean 'lazy'?" in res.stderr
    assert not (tmp_path / "o").exists()
    res = runner.invoke(app, ["bench", "--planners", "lazy,gco-orig", "--out",
                              str(tmp_path / "b"), "--dry-run"])
    assert res.exit_code == 2 and "did you mean 'gco-ori'?" in res.stderr
    res = runner.invoke(app, ["bench", "--suites", "rando", "--out", str(tmp_path / "b"),
                              "--dry-run"])
    assert res.exit_code == 2 and "did you mean 'random'?" in res.stderr
    res = runner.invoke(app, ["suite", "export", "mazee", str(tmp_path / "s")])
    assert res.exit_code == 2 and "did you mean 'maze'?" in res.stderr


# --------------------------------------------------------------------------- --model


def test_bad_model_values_exit_2_before_planning(small: Path, tmp_path: Path,
                                                 no_planning) -> None:
    junk = tmp_path / "junk.pt"
    junk.write_bytes(b"not a checkpoint")
    cases = [("learnd", "did you mean 'learned'?"),
             (str(tmp_path / "missing.pt"), "no such checkpoint file"),
             (str(junk), "not a usable lamp checkpoint"),
             (str(tmp_path), "is not a file")]
    for value, message in cases:
        for cmd in (["run", str(small)], ["demo"], ["model", "eval"],
                    ["bench", "--suites", "iros", "--dry-run"]):
            res = runner.invoke(app, [*cmd, "--model", value, "--out", str(tmp_path / "o")])
            assert res.exit_code == 2, (cmd, value, res.output)
            assert "--model: " in res.stderr and message in res.stderr, res.stderr
            assert "Traceback" not in res.output
    assert not (tmp_path / "o").exists()


def test_a_trained_checkpoint_works_in_run_and_bench(small: Path, tmp_path: Path) -> None:
    """``lamp model train``'s RUN_DIR/model.pt is accepted by run (which plans with it) and
    bench; eval reads it too."""
    from lamp.manip.dataset import synthetic_dataset
    from lamp.manip.network import NetConfig
    from lamp.manip.train import TrainConfig, train

    tiny = NetConfig(image_size=32, channels=(4, 8), image_dim=16, token_dim=8, traj_dim=32,
                     cond_dim=16, time_dim=16, hidden=64, blocks=1)
    train(synthetic_dataset(48, seed=0), tmp_path / "m", TrainConfig(epochs=1, seed=0,
          images_per_step=16, draws_per_image=2), tiny, progress=False)
    ckpt = tmp_path / "m" / "model.pt"
    out = tmp_path / "run"
    res = runner.invoke(app, ["run", str(small), "--model", str(ckpt), "--planning-limit", "2",
                              "-o", str(out)])
    assert res.exit_code == 0, res.output
    result = json.loads((out / "result.json").read_text())
    assert result["stats"]["model_calls"] > 0
    res = runner.invoke(app, ["bench", "--suites", "iros", "--model", str(ckpt), "--dry-run",
                              "--out", str(tmp_path / "b")])
    assert res.exit_code == 0, res.output


# --------------------------------------------------------------------------- lamp run


def test_run_progress_quiet_verbose_and_summary(small: Path, tmp_path: Path) -> None:
    out = tmp_path / "o"
    res = runner.invoke(app, ["run", str(small), "-m", "geometric", "-o", str(out)])
    assert res.exit_code == 0, res.output
    # not a terminal: no status line, a line per object done
    assert res.stderr.strip().splitlines()[-1].startswith("object 1/1: reached its goal")
    # a fresh environment also announces its one-time compilation ("not counted as
    # planning"): that line aside, no per-segment status
    lines = [ln for ln in res.stderr.splitlines() if "Numba kernels" not in ln]
    assert not any("planning" in ln or ": segment" in ln for ln in lines)
    d = json.loads((out / "result.json").read_text())
    # the one per-segment figure printed is the report's (total planning / segments)
    from lamp.bench.report import scenario_planning_time

    per = scenario_planning_time(d, float("inf"))[0]
    assert d["planning_time_per_segment_s"] == pytest.approx(per, abs=1e-6)
    assert f"({d['planning_time_per_segment_s']:.3f} s per segment)" in res.stdout
    assert "median" not in res.stdout
    res = runner.invoke(app, ["run", str(small), "-m", "geometric", "-o", str(out), "-v"])
    assert res.exit_code == 0
    assert "object 1/1: planning" in res.stderr
    assert f"object 1/1: segment {d['segments']}," in res.stderr
    assert "object 1/1: reached its goal" in res.stderr
    res = runner.invoke(app, ["run", str(small), "-m", "geometric", "-o", str(out), "-q"])
    assert res.exit_code == 0 and res.output == ""
    assert json.loads((out / "result.json").read_text())["success"]
    res = runner.invoke(app, ["run", str(small), "-q", "-v"])
    assert res.exit_code == 2


def test_progress_on_a_terminal_is_a_status_line() -> None:
    import io

    from lamp.cli.support import RunProgress
    from lamp.progress import ProgressEvent

    stream = io.StringIO()
    with RunProgress(stream=stream, terminal=True) as progress:
        assert progress.live
        progress(ProgressEvent("object", 0, 2))
        progress(ProgressEvent("segment", 0, 2, segments=3, replans=1))
        progress(ProgressEvent("object-done", 0, 2, segments=3, replans=1, success=True))
    text = stream.getvalue()
    assert "object 1/2: segment 3, 1 replans" in text
    assert "object 1/2: reached its goal after 3 segments, 1 replans" in text
    piped = io.StringIO()  # piped: no status line, a line per object done
    with RunProgress(stream=piped, terminal=False) as progress:
        progress(ProgressEvent("segment", 0, 2, segments=3))
        progress(ProgressEvent("compiling"))
        progress(ProgressEvent("object-done", 1, 2, segments=4, success=False))
    assert piped.getvalue().strip().splitlines() == [
        ProgressEvent("compiling").describe(), "object 2/2: failed after 4 segments, 0 replans"]


def test_check_exits_1_when_the_task_failed(tmp_path: Path) -> None:
    walled = small_scene(goal=(1.9, 1.0, 0.0))  # behind a wall across the whole workspace
    walled["obstacles"] = [{"type": "rectangle", "center": [1.6, 1.0], "size": [0.1, 2.0]}]
    far = tmp_path / "far.yaml"
    far.write_text(json.dumps(walled))
    args = ["run", str(far), "-m", "geometric", "--planning-limit", "0.5", "-q"]
    res = runner.invoke(app, [*args, "-o", str(tmp_path / "a")])
    assert res.exit_code == 0
    d = json.loads((tmp_path / "a" / "result.json").read_text())
    assert not d["success"]
    # all planning counts, also the search that found nothing to execute
    assert d["total_planning_time_s"] == pytest.approx(
        d["executed_planning_time_s"] + d["unexecuted_planning_time_s"], abs=2e-6)
    assert d["unexecuted_planning_time_s"] > 0
    res = runner.invoke(app, [*args, "--check", "-o", str(tmp_path / "b")])
    assert res.exit_code == 1
    assert (tmp_path / "b" / "result.json").is_file()


def test_check_exits_0_on_success(small: Path, tmp_path: Path) -> None:
    res = runner.invoke(app, ["run", str(small), "-m", "geometric", "--check", "-q",
                              "-o", str(tmp_path / "o")])
    assert res.exit_code == 0
    assert json.loads((tmp_path / "o" / "result.json").read_text())["success"]


def test_bad_out_fails_before_planning(small: Path, tmp_path: Path, no_planning) -> None:
    afile = tmp_path / "afile"
    afile.write_text("x")
    for out, message in ((afile, "exists and is not a folder"),
                         (afile / "sub", "is not a folder"),
                         (Path("/proc/lamp-no-such/out"), "cannot write to")):
        for cmd in (["run", str(small)], ["demo"]):
            res = runner.invoke(app, [*cmd, "--out", str(out)])
            assert res.exit_code == 2, res.output
            assert res.stderr.startswith("error: --out: ") and message in res.stderr
    assert afile.read_text() == "x" and sorted(p.name for p in tmp_path.iterdir()) == [
        "afile", "small.yaml"]


# --------------------------------------------------------------------------- validate, schema


def test_validate_good_and_bad_files(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(SPEC.read_text().replace("radius: 0.20", "radius: -0.2"))
    res = runner.invoke(app, ["validate", str(SPEC), str(DATA / "minimal.json")])
    assert res.exit_code == 0, res.output
    assert res.stdout.splitlines() == [
        f"ok {SPEC}: maze-07: 4 x 4 m, 3 robots, 3 objects, 3 obstacles",
        f"ok {DATA / 'minimal.json'}: minimal-json: " + res.stdout.splitlines()[1].split(
            "minimal-json: ")[1],
        "2 of 2 scene files valid"]
    res = runner.invoke(app, ["validate", str(SPEC), str(bad), str(tmp_path / "none.yaml")])
    assert res.exit_code == 2
    assert f"ok {SPEC}:" in res.stdout and "1 of 3 scene files valid" in res.stdout
    assert f"error: {bad}: objects[1].radius: must be > 0, got -0.2" in res.stderr
    assert "none.yaml: (file): file not found" in res.stderr


def test_validate_a_folder(tmp_path: Path) -> None:
    res = runner.invoke(app, ["suite", "export", "iros", str(tmp_path / "iros")])
    assert res.exit_code == 0
    res = runner.invoke(app, ["validate", str(tmp_path / "iros")])
    assert res.exit_code == 0, res.output
    n = len(list((tmp_path / "iros").glob("*.yaml")))
    assert n > 0 and f"{n} of {n} scene files valid" in res.stdout
    res = runner.invoke(app, ["validate", str(tmp_path)])  # holds no scene file itself
    assert res.exit_code == 2 and "no scene files" in res.stderr


def test_schema_accepts_valid_scenes_and_rejects_structural_errors() -> None:
    import jsonschema
    import yaml

    res = runner.invoke(app, ["schema"])
    assert res.exit_code == 0
    schema = json.loads(res.stdout)
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    spec = yaml.safe_load(SPEC.read_text())
    validator.validate(spec)
    validator.validate(json.loads((DATA / "minimal.json").read_text()))
    from lamp.suites.registry import SUITES, suite_files

    for name in SUITES:  # every built-in scene file, as written
        for path in suite_files(name):
            validator.validate(yaml.safe_load(Path(path).read_text()))
    for broken in ({**spec, "formatt": "x"}, {**spec, "workspace": [4.0, -1.0]},
                   {**spec, "objects": []},
                   {**spec, "robots": {"starts": [[0.3, 0.3]], "radius": 0}},
                   {**spec, "objects": [{**spec["objects"][0], "type": "triangle"}]}):
        assert not validator.is_valid(broken), broken


# --------------------------------------------------------------------------- warm-up


def _cache_without(cache: Path, dropped: Path) -> None:
    """Fill the Numba cache folder ``cache`` (``NUMBA_CACHE_DIR`` layout) with this
    checkout's compiled kernels, except those of the source file ``dropped``: a process
    using it compiles just those (a fully empty cache costs 20-40 s)."""
    from numba.core.caching import _CacheLocator

    from lamp.pipeline.warmup import ensure_warm

    ensure_warm()  # every kernel compiled (or loaded) into this checkout's __pycache__
    for folder in Path(lamp.__file__).parent.rglob("__pycache__"):
        for f in folder.iterdir():
            source = folder.parent / (f.name.split(".")[0] + ".py")
            if f.suffix in (".nbi", ".nbc") and source.is_file() and source != dropped:
                dest = cache / _CacheLocator.get_suitable_cache_subpath(str(source))
                dest.mkdir(parents=True, exist_ok=True)
                shutil.copy2(f, dest / f.name)


def test_compilation_is_announced_and_not_planning_time(tmp_path: Path) -> None:
    """With kernels missing from the Numba cache, ``lamp run`` says it compiles, keeps that
    out of the planning time, and leaves the cache warm for ``lamp warmup`` (and every later
    run)."""
    from lamp.mrmp import distance_field

    _cache_without(tmp_path / "cache", Path(distance_field.__file__))
    scene = tmp_path / "small.yaml"
    scene.write_text(json.dumps(small_scene()))
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "PYTHONPATH": os.pathsep.join([str(Path(lamp.__file__).parents[1]),
                                          os.environ.get("PYTHONPATH", "")])}
    cmd = [sys.executable, "-m", "lamp.cli"]
    res = subprocess.run([*cmd, "run", str(scene), "-m", "geometric", "-o", str(tmp_path / "o")],
                         env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "compiling Numba kernels" in res.stderr
    compiled = re.search(r"compiled Numba kernels in ([0-9.]+) s", res.stderr)
    assert compiled, res.stderr
    d = json.loads((tmp_path / "o" / "result.json").read_text())
    assert d["success"] and d["total_planning_time_s"] < float(compiled.group(1))
    res = subprocess.run([*cmd, "warmup"], env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    assert "already compiled" in res.stdout and "compiling" not in res.stderr


def test_built_in_scenes_by_name(tmp_path: Path) -> None:
    """``lamp show maze-07`` and ``lamp run maze-07`` take a built-in scene by name; an
    unknown name exits 2 naming it."""
    res = runner.invoke(app, ["show", "maze-07", "--out", str(tmp_path / "m.png")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "m.png").stat().st_size > 0
    res = runner.invoke(app, ["run", "maze-99x", "-o", str(tmp_path / "o")])
    assert res.exit_code == 2 and "maze-99x" in res.output
    assert not (tmp_path / "o").exists()
