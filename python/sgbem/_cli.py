"""`sgbem.run`: the command line `sgbem run` from Python."""

import json
import math
import os
import pathlib
import shutil
import subprocess

from ._archive import Run


class SgbemError(RuntimeError):
    """`sgbem run` ended with a non-zero exit status. `message` is what the command line
    printed (its `sgbem: ...` lines), `returncode` its exit status (2 invalid input,
    3 numerical failure or mechanism, 1 anything else), `out` the run folder when the run
    wrote one (a failed contact solve still writes every output)."""

    def __init__(self, message, returncode, out=None):
        super().__init__(message)
        self.message, self.returncode, self.out = message, returncode, out


def executable(exe=None):
    """The sgbem executable: `exe`, else $SGBEM, else the repository's
    target/release/sgbem (this package lives in its python/ folder), else `sgbem` on PATH."""
    candidates = [exe, os.environ.get("SGBEM"),
                  pathlib.Path(__file__).resolve().parents[2] / "target" / "release" / "sgbem",
                  shutil.which("sgbem")]
    for c in candidates:
        if c and pathlib.Path(c).is_file() and os.access(c, os.X_OK):
            return str(c)
    if exe or os.environ.get("SGBEM"):
        raise FileNotFoundError(f"sgbem executable {exe or os.environ['SGBEM']!r} not found")
    raise FileNotFoundError("no sgbem executable: build it (`cargo build --release` in the "
                            "repository), put it on PATH, or set SGBEM to its path")


def toml_value(value):
    """A Python value as the TOML text of `--set KEY=VALUE`."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a TOML basic string
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    raise TypeError(f"--set value {value!r}: give a bool, number, string or list")


def run(scene, out=None, set=None, mesh=None, method=None, exe=None):  # noqa: A002
    """Runs `sgbem run SCENE` and opens its run folder (a `Run`).

    `out` the output folder (else the scene's `output.directory`), `set` a dict of scene
    overrides {"interface.joint.cohesion": 2.0} (values as Python bool, number, string or
    list), `mesh` a mesh file, `method` "lcp", "qp", "both", "sparse" or "exact", `exe` the
    executable (see `executable`). Raises `SgbemError` with the command line's message on a
    non-zero exit.
    """
    argv = [executable(exe), "run", str(scene)]
    if out is not None:
        argv += ["--out", str(out)]
    if mesh is not None:
        argv += ["--mesh", str(mesh)]
    if method is not None:
        argv += ["--method", str(method)]
    for key, value in (set or {}).items():
        argv += ["--set", f"{key}={toml_value(value)}"]
    # Not --quiet: stdout then names the folder ("results in DIR"); with stdout and stderr
    # captured there are no progress bars.
    proc = subprocess.run(argv, capture_output=True, text=True, check=False)
    folder = pathlib.Path(out) if out is not None else None
    for line in proc.stdout.splitlines():
        if line.startswith("results in "):
            folder = pathlib.Path(line[len("results in "):])
    if proc.returncode != 0:
        lines = [ln for ln in proc.stderr.splitlines() if ln.startswith("sgbem:")]
        message = "\n".join(lines or proc.stderr.strip().splitlines()[-5:]) or \
            f"sgbem run {scene} ended with exit status {proc.returncode}"
        # Exit 3 (a failed solve, a mechanism) still writes every output.
        written = folder if proc.returncode == 3 and folder is not None \
            and (folder / "archive.h5").is_file() else None
        raise SgbemError(message, proc.returncode, written)
    if folder is None:
        raise SgbemError(f"sgbem run {scene} did not say where it wrote its results", 0)
    return Run(folder)
