"""Type stubs of the native module ellipack._ellipack (the Rust part of the package)."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str
_MAX_ITEMS: int

class NotReached(ValueError):
    """A container of fixed size that the run did not fill without overlap before its time
    limit (or Ctrl-C); ``packing`` is the least overlapping configuration (not a packing)."""

    packing: Packing

class Packing:
    """A packing: container and items, with the summary of the run or folder that made it."""

    @property
    def dimension(self) -> int:
        """2 (ellipses) or 3 (ellipsoids)."""
    def __len__(self) -> int: ...
    @property
    def centres(self) -> npt.NDArray[np.float64]:
        """The centres, shape (m, dimension)."""
    @property
    def semi_axes(self) -> npt.NDArray[np.float64]:
        """The semi-axes, shape (m, dimension); semi-axis k lies along column k of the
        rotation."""
    @property
    def quaternions(self) -> Optional[npt.NDArray[np.float64]]:
        """3D: unit quaternions (w, x, y, z), shape (m, 4); 2D: None."""
    @property
    def angles(self) -> Optional[npt.NDArray[np.float64]]:
        """2D: angles theta (radians), shape (m,); 3D: None."""
    @property
    def container(self) -> Dict[str, Any]:
        """``kind``, ``center`` and ``radius``, ``semi_axes`` or ``half_sides``."""
    @property
    def density(self) -> float:
        """Total item area or volume over the container's."""
    @property
    def certificate(self) -> Dict[str, Any]:
        """``overlapping_pairs``, ``containment_violations``, ``min_mu2``."""
    @property
    def summary(self) -> Dict[str, Any]:
        """summary.json as a dict."""
    @property
    def interrupted(self) -> bool:
        """True when Ctrl-C stopped the run that made it."""
    @property
    def history(self) -> Optional[str]:
        """history.csv of the run; None for a packing read from a folder."""
    def write(self, folder: Union[str, PathLike[str]], xyz: bool = True) -> None:
        """Writes packing.csv, summary.json, packing.xyz and history.csv into ``folder``, as
        one set."""

def read_packing(folder: Union[str, PathLike[str]]) -> Packing:
    """The packing of a folder (packing.csv and summary.json)."""

def verify(packing: Packing) -> Dict[str, Any]:
    """``certified``, ``overlapping_pairs`` [(i, j, mu2)], ``outside`` [(i, t)], ``min_mu2``."""

def _rows(
    kind: str,
    inputs: List[npt.NDArray[np.float64]],
    out: npt.NDArray[np.float64],
    threads: int,
    batch: bool,
) -> None: ...
def _bench_rust_batch(
    r12: npt.NDArray[np.float64],
    q1: npt.NDArray[np.float64],
    q2: npt.NDArray[np.float64],
    all_threads: bool,
) -> float: ...
def _pack(
    scene: Union[str, Dict[str, Any], None],
    path: Optional[str],
    time_limit: Optional[float],
    seed: Optional[int],
    threads: Optional[int],
    progress: Optional[Callable[[Dict[str, Any]], Any]],
) -> Packing: ...
def _container_dimension(container_json: str) -> int: ...
def _packing_from_arrays(
    container_json: str,
    centres: npt.NDArray[np.float64],
    semi_axes: npt.NDArray[np.float64],
    orientations: npt.NDArray[np.float64],
) -> Packing: ...
def _analyse(
    packing: Packing,
    gap: float,
    bond_cutoff: Optional[float],
    rdf_range: Optional[float],
    rdf_bins: int,
) -> Tuple[str, List[float], List[float]]: ...
