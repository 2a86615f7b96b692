"""ndcontour: the common zero set of n - k polynomial constraints in n variables.

The zero set M is computed as a polyline (k = 1) or a triangle mesh (k = 2) in any dimension n,
with the topology certified where it is proven (docs/python.md, docs/certificate.md)::

    import ndcontour
    r = ndcontour.solve("experiments/problems/torus.toml", depth=5)
    r.vertices, r.simplices, r.summary["topology"]["certified"]

`solve` takes a problem file's path, its TOML text, or a dict of its tables (numpy arrays and
numbers welcome); every option of ``ndcontour solve`` is a keyword.
"""

from __future__ import annotations

import os
import sys
import time
from typing import Any, Callable, Mapping, Optional, Union

from . import _core
from ._core import ExpectationWarning, InputError, Result

__all__ = ["solve", "Result", "InputError", "ExpectationWarning", "ProblemLike", "__version__"]
__version__: str = _core.__version__

# The classes live in the extension; they are ndcontour's for help() and repr().
for _cls in (Result, InputError, ExpectationWarning):
    _cls.__module__ = __name__

#: What `solve` accepts as a problem: a path, the text of a problem file (a str with a line
#: break), or a dict of its tables.
ProblemLike = Union[str, "os.PathLike[str]", Mapping[str, Any]]

#: A progress callable: called with the stage ("subdivision", "projection", "connection, round
#: 2: ...", "analysis") and the fraction of it done, in [0, 1]; every stage ends with 1.0.
ProgressCallback = Callable[[str, float], None]


def solve(
    problem: ProblemLike,
    *,
    depth: int = 6,
    max_depth: Optional[int] = None,
    tolerance: Optional[float] = None,
    bounding: str = "linearized",
    subdivision: str = "binary",
    projection: str = "newton",
    classification: str = "paper",
    connection: str = "crossing",
    scalar: str = "double",
    precision: Optional[int] = None,
    jitter: Optional[int] = None,
    max_memory: Union[str, int, None] = None,
    threads: Optional[int] = None,
    timeout: Optional[float] = None,
    progress: Union[bool, ProgressCallback, None] = None,
) -> Result:
    """Solve a problem and return its mesh, summary and files as a `Result`.

    Args:
        problem: a problem file's path (`str` or `os.PathLike`), its TOML text (a `str` with a
            line break), or a dict of its keys and tables (``{"variables": [...], "domain":
            [...], "equations": [...], "expect": {...}}`` or an application's tables). Values
            may be numpy arrays and numpy numbers; ``name`` may be left out (it is then
            "problem").
        depth: the subdivision depth: the grid has 2^depth cells per axis (``--depth``).
        max_depth: the deepest level adaptive refinement may reach (``--max-depth``; None: depth
            + 10, or less where n * level > 128; equal to depth: no refinement).
        tolerance: the chord error the mesh should stay below (``--tolerance``; None: none).
        bounding, subdivision, projection, classification, connection: the strategy of each
            stage by name, with parameters as ``"name:key=value"`` (``ndcontour info``).
        scalar: ``"double"`` or ``"mpfr"`` (multiprecision, ``precision`` bits; default 128).
        precision: the MPFR precision in bits (``--precision``).
        jitter: a seed that perturbs the grid, for ablation (``--jitter``; None: none).
        max_memory: the memory the run may use, e.g. ``"4G"`` or a number of bytes.
        threads: worker threads (None: every hardware thread).
        timeout: seconds after which the run stops with `TimeoutError` (None: no limit).
        progress: None (the default) draws a bar on standard error when it is a terminal;
            False draws nothing; True always draws it; a callable ``progress(stage, fraction)``
            is called instead, on the calling thread, every 50 ms at most and at the end of
            each stage (an exception it raises stops the run and propagates).

    Returns:
        a `Result`: ``vertices`` (N, n), ``simplices`` (M, k + 1), ``image`` (N, 3),
        ``variables``, ``summary`` (the dict of summary.json) and ``write(dir)``.

    Raises:
        InputError: bad input (a `ValueError` with the message ``ndcontour solve`` prints).
        TypeError: an option of the wrong type.
        TimeoutError: ``timeout`` passed.
        KeyboardInterrupt: Ctrl-C, within one work item of any stage.
        MemoryError: out of memory.

    Warns:
        ExpectationWarning: for each ``[expect]`` key the mesh does not match.
        UserWarning: when the zero set does not meet the domain.
    """
    options = dict(depth=depth, max_depth=max_depth, tolerance=tolerance, bounding=bounding,
                   subdivision=subdivision, projection=projection,
                   classification=classification, connection=connection, scalar=scalar,
                   precision=precision, jitter=jitter, max_memory=max_memory, threads=threads,
                   timeout=timeout)
    options = {name: _plain(value) for name, value in options.items()}  # numpy numbers too
    return _core.solve(_problem_of(problem), _progress_of(progress), **options)


def _problem_of(problem: Any) -> Any:
    """A dict problem with numpy values turned into Python ones and a default name."""
    if not isinstance(problem, Mapping):
        return problem
    converted = {k: _plain(v) for k, v in problem.items()}
    converted.setdefault("name", "problem")
    return converted


def _plain(value: Any) -> Any:
    """`value` with numpy arrays as (nested) lists and numpy scalars as Python numbers."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    tolist = getattr(value, "tolist", None)  # numpy.ndarray and numpy scalars
    if tolist is not None and type(value).__module__ == "numpy":
        return tolist()
    return value


def _progress_of(progress: Union[bool, ProgressCallback, None]) -> Optional[ProgressCallback]:
    """The callable the extension calls: the user's, a terminal bar, or None."""
    if progress is None:
        progress = _stderr_is_terminal()
    if progress is True:
        return _TerminalBar(sys.stderr)
    if progress is False:
        return None
    if not callable(progress):
        raise TypeError("solve(): progress must be callable, True, False or None, not "
                        + type(progress).__name__)
    return progress


def _stderr_is_terminal() -> bool:
    try:
        return sys.stderr is not None and sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class _TerminalBar:
    """The CLI's progress bar: one line per stage, redrawn at most ten times a second."""

    width = 30

    def __init__(self, stream: Any) -> None:
        self.stream = stream
        self.stage: Optional[str] = None
        self.fraction = 0.0
        self.drawn = 0.0

    def __call__(self, stage: str, fraction: float) -> None:
        now = time.monotonic()
        if stage == self.stage and fraction < 1.0 and now - self.drawn < 0.1:
            return
        if self.stage is not None and stage != self.stage and self.fraction < 1.0:
            self.stream.write("\n")  # a stage left unfinished keeps its line
        self.stage, self.fraction, self.drawn = stage, fraction, now
        filled = int(round(self.width * max(0.0, min(1.0, fraction))))
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write("\r%s [%s] %3d%%\033[K" % (stage, bar, int(100 * fraction)))
        if fraction >= 1.0:
            self.stream.write("\n")
        self.stream.flush()
