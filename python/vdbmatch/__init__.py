"""vdbmatch: smooth, invertible deformations matching one closed surface onto another.

The symmetric thin-shell matching of Iglesias (*Symmetry and scaling limits for matching of
implicit surfaces based on thin shell energies*): given shapes M1 and M2, ``match`` finds
phi: Omega -> Omega minimising E^sigma = E_match + E_mem + E_bend + E_vol (paper eq:Esym) on
multiscale piecewise-linear lattices, so that phi(M1) fits M2 and its exact inverse maps M2 back.

This module runs the same code as the ``vdb_match`` command, in this process, with the same
parameters, defaults, outputs and messages (docs/cli.md, docs/python.md):

    import vdbmatch
    r = vdbmatch.match("a.vdb", "b.vdb", levels="4..7")
    print(r.report["result"]["residual"])
    moved = r.apply(points)                  # phi on an (n, d) array
    back = r.apply(moved, inverse=True)      # the exact inverse
    r.save("out/")                           # deformation.vdb, inverse.vdb, ... report.json

A shape is a file path (.vdb level set, .obj/.ply/.stl mesh, .polyline curve), a pyopenvdb
FloatGrid level set, a triangle mesh as numpy arrays ``(V, F)``, or a closed 2D polyline as an
(n, 2) array (a list of them for several curves).
"""

from __future__ import annotations

import difflib
import json
import os
import shutil
import tempfile
import threading
import warnings
import weakref

import numpy as np

from . import _vdbmatch

__version__ = _vdbmatch.__version__
__all__ = [
    "match",
    "energy",
    "consistency",
    "load",
    "MatchResult",
    "NotConvergedError",
    "options",
    "__version__",
]

# Options each function sets itself: not keywords.
_RESERVED = {
    "match": {"--output", "--source", "--target", "--quiet", "--progress-every"},
    "energy": {"--source", "--target", "--json", "--quiet"},
    "consistency": {"--source", "--target", "--json"},
}

# Files of a match result (report.json lists those a run wrote).
_RESULT_FILES = (
    "deformation.vdb",
    "inverse.vdb",
    "jacobian.vdb",
    "deformed.vdb",
    "deformed.obj",
    "report.json",
)


class NotConvergedError(RuntimeError):
    """``match(..., strict=True)`` ended a level without convergence (exit code 4)."""


def options(command: str = "match") -> list[dict]:
    """The options of a ``vdb_match`` command as dicts (name, metavar, values, group, help).

    The keywords of :func:`match`, :func:`energy` and :func:`consistency` are these names
    without the leading dashes and with ``_`` for ``-`` (``--energy-tolerance`` is
    ``energy_tolerance``); the help text states each default.
    """
    return [dict(o) for o in _vdbmatch.options(command)]


def _keyword(name: str) -> str:
    return name.lstrip("-").replace("-", "_")


def _keyword_table(command: str) -> dict[str, dict]:
    reserved = _RESERVED.get(command, set())
    return {_keyword(o["name"]): o for o in _vdbmatch.options(command) if o["name"] not in reserved}


# ---------------------------------------------------------------------------- inputs


def _is_grid(obj) -> bool:
    return type(obj).__module__ == "pyopenvdb" and hasattr(obj, "activeVoxelCount")


def _write_points_csv(points, path: str, dim: int | None = None) -> str:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] not in (2, 3) or (dim is not None and p.shape[1] != dim):
        raise ValueError(f"points: expected an (n, 2) or (n, 3) array, got shape {p.shape}")
    names = "x,y,z"[: 2 * p.shape[1] - 1]
    with open(path, "w") as f:
        f.write(names + "\n")
        for row in p:
            f.write(",".join(repr(float(v)) for v in row) + "\n")
    return path


def _write_polyline(curves, path: str) -> str:
    with open(path, "w") as f:
        f.write("# vdbmatch polyline written by the Python module\n")
        for k, c in enumerate(curves):
            c = np.asarray(c, dtype=np.float64)
            if c.ndim != 2 or c.shape[1] != 2 or c.shape[0] < 3:
                raise ValueError(f"curve {k}: expected an (n, 2) array with n >= 3, got shape {c.shape}")
            if not np.all(np.isfinite(c)):
                raise ValueError(f"curve {k}: the points must be finite")
            if k:
                f.write("\n")
            for x, y in c:
                f.write(f"{float(x)!r} {float(y)!r}\n")
    return path


def _write_obj(V, F, path: str) -> str:
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"mesh vertices: expected an (n, 3) array, got shape {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3 or not np.issubdtype(F.dtype, np.integer):
        raise ValueError(f"mesh faces: expected an (m, 3) integer array, got {F.dtype} {F.shape}")
    if not np.all(np.isfinite(V)):
        raise ValueError("mesh vertices must be finite")
    if F.size and (F.min() < 0 or F.max() >= len(V)):
        raise ValueError(f"mesh faces index vertices outside 0..{len(V) - 1}")
    with open(path, "w") as f:
        f.write("# written by the vdbmatch Python module\n")
        for x, y, z in V:
            f.write(f"v {float(x)!r} {float(y)!r} {float(z)!r}\n")
        for a, b, c in F + 1:
            f.write(f"f {a} {b} {c}\n")
    return path


def _shape_file(shape, folder: str, name: str) -> str:
    """A file the command reads for @a shape (a path, a grid, a mesh or curves)."""
    if isinstance(shape, (str, os.PathLike)):
        return os.fspath(shape)
    if _is_grid(shape):
        import pyopenvdb

        path = os.path.join(folder, name + ".vdb")
        pyopenvdb.write(path, grids=[shape])
        return path
    if isinstance(shape, np.ndarray):
        if shape.ndim == 2 and shape.shape[1] == 2:
            return _write_polyline([shape], os.path.join(folder, name + ".polyline"))
        raise ValueError(f"{name}: an array shape must be an (n, 2) polyline, got shape {shape.shape}")
    if isinstance(shape, (tuple, list)):
        if len(shape) == 2 and np.ndim(shape[1]) == 2 and np.asarray(shape[1]).shape[1] == 3 \
                and np.asarray(shape[0]).shape[-1] == 3:
            return _write_obj(shape[0], shape[1], os.path.join(folder, name + ".obj"))
        if len(shape) > 0 and all(np.ndim(c) == 2 and np.shape(c)[1] == 2 for c in shape):
            return _write_polyline(shape, os.path.join(folder, name + ".polyline"))
    raise TypeError(
        f"{name}: expected a file path, a pyopenvdb FloatGrid, a mesh (V, F) or an (n, 2) "
        f"polyline, got {type(shape).__name__}"
    )


def _arguments(command: str, parameters: dict, folder: str) -> list[str]:
    """The command-line options for keyword @a parameters of @a command."""
    table = _keyword_table(command)
    args: list[str] = []
    for key, value in parameters.items():
        opt = table.get(key)
        if opt is None:
            close = difflib.get_close_matches(key, table.keys(), n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise TypeError(f"{command}() got an unexpected keyword argument '{key}'{hint}")
        if value is None:
            continue
        name, values = opt["name"], opt["values"]
        if values == 0:
            if not isinstance(value, (bool, np.bool_)):
                raise TypeError(f"{key}: a flag takes True or False, got {value!r}")
            if value:
                args.append(name)
            continue
        items = list(value) if values > 1 and not isinstance(value, str) else [value]
        if len(items) != values:
            raise ValueError(f"{key}: expected {values} values ({opt['metavar']}), got {len(items)}")
        args.append(name)
        for k, item in enumerate(items):
            if isinstance(item, (bool, np.bool_)):
                raise TypeError(f"{key}: expected {opt['metavar']}, got {item!r}")
            if isinstance(item, np.ndarray) and key == "landmarks":
                item = _write_points_csv(item, os.path.join(folder, f"landmarks{k}.csv"))
            elif key in ("init", "warm_start") and isinstance(item, MatchResult):
                item = os.path.join(item.folder, "deformation.vdb")
            elif isinstance(item, (float, np.floating)):
                item = repr(float(item))
            elif isinstance(item, os.PathLike):
                item = os.fspath(item)
            args.append(str(item))
    return args


# ---------------------------------------------------------------------------- running


def _tqdm_progress():
    """A tqdm bar over the levels, when tqdm is installed; else None."""
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None
    state = {}

    def update(e):
        if "bar" not in state and e["kind"] in ("level_start", "iteration"):
            state["bar"] = tqdm(total=e["last_level"] - e["first_level"] + 1, unit="level",
                                desc="vdbmatch")
        bar = state.get("bar")
        if bar is None:
            return
        if e["kind"] == "iteration":
            bar.set_postfix(level=e["level"], it=e["iteration"], E=f"{e['energy']:.4g}",
                            refresh=False)
            bar.update(0)  # redraws at most every mininterval
        elif e["kind"] == "level_end":
            bar.update(1)
            if e["level"] == e["last_level"]:
                bar.close()

    return update


def _run(args: list[str], progress=None) -> tuple[str, str]:
    """Runs a command; returns (stdout, stderr) or raises as the exit code says."""
    on_main = threading.current_thread() is threading.main_thread()
    code, out, err = _vdbmatch.run(args, progress, on_main)
    if code == _vdbmatch.EXIT_OK:
        return out, err
    lines = [ln for ln in err.splitlines() if ln.startswith("vdb_match: error: ")]
    message = lines[-1][len("vdb_match: error: "):] if lines else err.strip() or f"exit code {code}"
    if code == _vdbmatch.EXIT_INTERRUPTED:
        raise KeyboardInterrupt(message)
    if code == _vdbmatch.EXIT_IO:
        raise OSError(message)
    if code == _vdbmatch.EXIT_NOT_CONVERGED:
        raise NotConvergedError("a level did not converge (strict=True)")
    raise ValueError(message)


class _Workspace:
    """A temporary folder removed when its owner is collected (or at exit)."""

    def __init__(self):
        self.path = tempfile.mkdtemp(prefix="vdbmatch-")
        self._finalizer = weakref.finalize(self, shutil.rmtree, self.path, True)

    def remove(self):
        self._finalizer()


def match(source, target, *, progress=None, **parameters) -> "MatchResult":
    """Matches M1 = source onto M2 = target (``vdb_match match``); returns a MatchResult.

    Shapes: a file path, a pyopenvdb FloatGrid level set, a mesh ``(V, F)`` (float (n, 3),
    integer (m, 3)), or a closed 2D polyline as an (n, 2) array (a list of them for several
    curves). Every option of ``vdb_match match`` is a keyword with the same name (``_`` for
    ``-``) and the same default (None: the command's default); see :func:`options` and the
    list below. ``landmarks`` takes two files or two (k, d) arrays.

    progress: None (a tqdm bar if tqdm is installed, else silent), False (silent), or a
    callable taking one dict per event: kind ("message", "level_start", "iteration",
    "level_end"), level, first_level, last_level, iteration, energy, elapsed, seconds_left,
    text. An exception raised by it stops the match and propagates.

    The GIL is released while matching. Ctrl-C raises KeyboardInterrupt within an iteration,
    and nothing is left behind. Bad input raises ValueError (OSError for unreadable files),
    with the command's message.
    """
    if progress is None:
        progress = _tqdm_progress()
    elif progress is False:
        progress = None
    work = _Workspace()
    try:
        inputs = os.path.join(work.path, "inputs")
        os.mkdir(inputs)
        src = _shape_file(source, inputs, "source")
        tgt = _shape_file(target, inputs, "target")
        out = os.path.join(work.path, "result")
        args = ["match", src, tgt, "-o", out, "--quiet"] + _arguments("match", parameters, inputs)
        _run(args, progress)
        return MatchResult(out, _workspace=work)
    except BaseException:
        work.remove()
        raise


def energy(source, target, **parameters) -> dict:
    """E^sigma[Id] and its terms for two shapes (``vdb_match energy --json``), as a dict."""
    work = _Workspace()
    try:
        src = _shape_file(source, work.path, "source")
        tgt = _shape_file(target, work.path, "target")
        args = ["energy", src, tgt, "--json", "--quiet"] + _arguments("energy", parameters, work.path)
        out, _ = _run(args)
        return json.loads(out)
    finally:
        work.remove()


def _deformation_path(phi) -> str:
    if isinstance(phi, MatchResult):
        return os.path.join(phi.folder, "deformation.vdb")
    if isinstance(phi, (str, os.PathLike)):
        return os.fspath(phi)
    raise TypeError(f"expected a MatchResult or a deformation.vdb path, got {type(phi).__name__}")


def _report_of(phi) -> dict | None:
    """The report.json next to a deformation, or None."""
    if isinstance(phi, MatchResult):
        return phi.report
    path = os.path.join(os.path.dirname(os.path.abspath(_deformation_path(phi))), "report.json")
    if os.path.isfile(path):
        with open(path) as f:
            return json.load(f)
    return None


def consistency(phi, psi, source=None, target=None, **parameters) -> dict:
    """|psi o phi - Id| on M1 and |phi o psi - Id| on M2 (``vdb_match consistency --json``).

    phi, psi: MatchResults or deformation.vdb paths of the two directions (source -> target
    and target -> source). source, target: the shapes M1 and M2; by default those phi was
    matched from, as its report.json names them (with their grids).
    """
    if source is None or target is None:
        report = _report_of(phi)
        if report is None:
            raise ValueError("consistency: give source and target (no report.json next to phi)")
        for key, given in (("source", source), ("target", target)):
            if given is None:
                entry = report[key]
                if key == "source":
                    source = entry["path"]
                else:
                    target = entry["path"]
                if entry.get("grid") and parameters.get(key + "_grid") is None:
                    parameters[key + "_grid"] = entry["grid"]
    work = _Workspace()
    try:
        args = ["consistency", _deformation_path(phi), _deformation_path(psi),
                "--source", _shape_file(source, work.path, "source"),
                "--target", _shape_file(target, work.path, "target"), "--json"]
        args += _arguments("consistency", parameters, work.path)
        out, _ = _run(args)
        return json.loads(out)
    finally:
        work.remove()


def load(folder) -> "MatchResult":
    """A result written by ``vdb_match match -o FOLDER`` or :meth:`MatchResult.save`."""
    folder = os.fspath(folder)
    for name in ("deformation.vdb", "report.json"):
        if not os.path.isfile(os.path.join(folder, name)):
            raise OSError(f"'{folder}' holds no match result (no {name})")
    return MatchResult(folder)


# ---------------------------------------------------------------------------- results


class MatchResult:
    """A match: phi as a displacement grid, its exact inverse, det D phi, the report.

    Attributes load on first use from the result's folder (a temporary one for
    :func:`match`, kept while this object lives; :meth:`save` copies it).
    """

    def __init__(self, folder: str, _workspace: _Workspace | None = None):
        self.folder = folder
        self._workspace = _workspace
        self._report = None
        self._deformation = None
        self._grids = {}

    def __repr__(self) -> str:
        r = self.report
        res = r.get("result", {})
        nan = float("nan")
        return (f"<vdbmatch.MatchResult {r.get('status', '?')}, energy {res.get('energy', nan):.6g}, "
                f"residual mean {res.get('residual', {}).get('meanUnit', nan):.3g}, target residual "
                f"mean {res.get('targetResidual', {}).get('meanUnit', nan):.3g} of the unit box>")

    @property
    def report(self) -> dict:
        """report.json as a dict: parameters, per-level figures, residuals, files."""
        if self._report is None:
            with open(os.path.join(self.folder, "report.json")) as f:
                self._report = json.load(f)
        return self._report

    def _grid(self, filename: str):
        """The grid of @a filename, read once (None if the run did not write the file)."""
        if filename not in self._grids:
            import pyopenvdb

            path = os.path.join(self.folder, filename)
            self._grids[filename] = pyopenvdb.readAll(path)[0][0] if os.path.isfile(path) else None
        return self._grids[filename]

    @property
    def displacement(self):
        """phi(x) - x as a pyopenvdb Vec3SGrid (grid ``displacement`` of deformation.vdb)."""
        return self._grid("deformation.vdb")

    @property
    def inverse_displacement(self):
        """phi^-1(y) - y as a pyopenvdb Vec3SGrid (inverse.vdb), or None if not written."""
        return self._grid("inverse.vdb")

    @property
    def jacobian(self):
        """det D phi per voxel cell as a pyopenvdb FloatGrid (jacobian.vdb), or None."""
        return self._grid("jacobian.vdb")

    def deformed_mesh(self):
        """phi(M1) from deformed.obj: (V, F) for a mesh, (V, E) for 2D curves (V is (n, 2),
        E the segments)."""
        V, F = [], []
        with open(os.path.join(self.folder, "deformed.obj")) as f:
            for line in f:
                parts = line.split()
                if not parts:
                    continue
                if parts[0] == "v":
                    V.append([float(x) for x in parts[1:4]])
                elif parts[0] in ("f", "l"):
                    F.append([int(p.split("/")[0]) - 1 for p in parts[1:]])
        V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
        if self.report.get("dimension") == 2:
            V = V[:, :2]
        return V, np.asarray(F, dtype=np.int64)

    def apply(self, points, inverse: bool = False) -> np.ndarray:
        """phi (or, with inverse=True, the exact phi^-1) on an (n, d) array of world points.

        Points outside the domain stay in place. Warns if an inverse walk met a simplex with
        det D phi <= 0 (the point is then approximate).
        """
        if self._deformation is None:
            self._deformation = _vdbmatch.Deformation(os.path.join(self.folder, "deformation.vdb"))
        mapped, failures = self._deformation.map(np.asarray(points, dtype=np.float64), bool(inverse))
        if failures:
            warnings.warn(f"the inverse walk failed at {failures} points (det D phi <= 0)",
                          RuntimeWarning, stacklevel=2)
        return mapped

    def save(self, folder) -> None:
        """Writes the result's files (those of ``vdb_match match -o``) into @a folder."""
        folder = os.fspath(folder)
        os.makedirs(folder, exist_ok=True)
        for name in _RESULT_FILES:
            src = os.path.join(self.folder, name)
            if not os.path.isfile(src):
                continue
            dst = os.path.join(folder, name)
            if os.path.abspath(src) == os.path.abspath(dst):
                continue
            tmp = dst + ".tmp-vdbmatch"
            try:
                shutil.copyfile(src, tmp)
                os.replace(tmp, dst)
            except BaseException:
                if os.path.exists(tmp):
                    os.remove(tmp)
                raise


def _document_keywords():
    """Appends every keyword of match/energy/consistency, with its help, to the docstrings."""
    for fn, command in ((match, "match"), (energy, "energy"), (consistency, "consistency")):
        lines = ["", "Keywords (the options of ``vdb_match " + command + "``):", ""]
        for key, o in _keyword_table(command).items():
            meta = f" {o['metavar']}" if o["metavar"] else " (flag)"
            lines.append(f"    {key}{meta}: {o['help']}")
        fn.__doc__ = (fn.__doc__ or "") + "\n".join(lines) + "\n"


_document_keywords()
