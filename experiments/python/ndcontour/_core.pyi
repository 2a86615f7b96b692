"""Type stubs of the extension `ndcontour._core` (experiments/python/ndcontour_module.cpp)."""

from typing import Any, Callable, Dict, List, Optional

import numpy as np
import numpy.typing as npt

__version__: str

class InputError(ValueError):
    """Bad input: the message is the line `ndcontour solve` prints for it."""

class ExpectationWarning(UserWarning):
    """A mesh that does not match the problem's [expect], or a key that cannot be compared."""

class Result:
    """The result of one solve (the outputs of `ndcontour solve`)."""

    @property
    def n(self) -> int: ...
    @property
    def k(self) -> int: ...
    @property
    def vertices(self) -> npt.NDArray[np.float64]: ...
    @property
    def simplices(self) -> npt.NDArray[np.int64]:
        """The k-simplices, (M, k + 1) vertex rows: segments, triangles, tetrahedra, ..."""
    @property
    def image(self) -> npt.NDArray[np.float64]: ...
    @property
    def image2(self) -> Optional[npt.NDArray[np.float64]]: ...
    @property
    def variables(self) -> List[str]: ...
    @property
    def summary(self) -> Dict[str, Any]: ...
    def write(self, dir: Any, *, ascii: bool = False, cells: bool = False, vtk: bool = False,
              vtk_legacy: bool = False, obj: bool = False) -> List[str]: ...

def _result_from_arrays(vertices: npt.ArrayLike, simplices: npt.ArrayLike,
                        variables: List[str] = ..., problem: str = ...) -> Result:
    """For tests: a Result of the mesh given (vertices (N, n), simplices (M, k + 1))."""
def solve(problem: Any, progress: Optional[Callable[[str, float], None]],
          **options: Any) -> Result: ...
def defaults() -> Dict[str, Any]: ...
