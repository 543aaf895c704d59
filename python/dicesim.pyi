"""Type stubs of the dicesim extension module (python/*.cpp). Docstrings: help(dicesim)."""
import os
from typing import Any, Callable, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

# A value of `set=`: written as TOML (a str goes through as TOML text, or a bare string).
SetValue = Union[bool, int, float, str, Sequence[Any]]
Overrides = Union[Mapping[str, SetValue], Iterable[str], None]
Progress = Optional[Callable[[int, int], Any]]
# A scene argument: a loaded Scene, or a path to load (as load_scene(path)).
SceneArg = Union["Scene", str, os.PathLike[str]]
# A count: an int, or a float that is a whole number (1e5).
Count = Union[int, float]

class SceneError(ValueError):
    """Bad scene input; str(e) is the CLI's exit-2 message."""
    file: str
    key: str
    value: str
    allowed: str

class Scene:
    @property
    def path(self) -> str: ...
    @property
    def overrides(self) -> list[str]: ...
    @property
    def name(self) -> str: ...
    @property
    def fidelity(self) -> str: ...
    @property
    def labels(self) -> list[int]: ...
    def info(self, fidelity: Optional[str] = None) -> dict[str, Any]: ...

class Result:
    @property
    def labels(self) -> npt.NDArray[np.int64]: ...
    @property
    def counts(self) -> npt.NDArray[np.int64]: ...
    @property
    def p(self) -> npt.NDArray[np.float64]: ...
    @property
    def ci95(self) -> npt.NDArray[np.float64]: ...  # shape (faces, 2)
    @property
    def settled(self) -> int: ...
    @property
    def unresolved(self) -> int: ...
    @property
    def invalid(self) -> int: ...
    @property
    def corrections(self) -> Optional[dict[str, Any]]: ...
    @property
    def chi2_uniform(self) -> dict[str, Any]: ...
    @property
    def elapsed_s(self) -> float: ...
    @property
    def tosses(self) -> int: ...
    @property
    def seed(self) -> int: ...
    @property
    def threads(self) -> int: ...
    @property
    def fidelity(self) -> str: ...
    @property
    def scene(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...
    def to_pandas(self) -> Any: ...  # pandas.DataFrame

class Sweep:
    @property
    def title(self) -> str: ...
    @property
    def key(self) -> str: ...
    @property
    def point_labels(self) -> list[str]: ...
    @property
    def values(self) -> npt.NDArray[np.float64]: ...
    @property
    def points(self) -> list[Result]: ...
    @property
    def overrides(self) -> list[list[str]]: ...
    @property
    def elapsed_s(self) -> float: ...
    def __len__(self) -> int: ...
    def __getitem__(self, i: int) -> Result: ...
    def to_pandas(self) -> Any: ...  # pandas.DataFrame, long form

def load_scene(path: str, set: Overrides = None) -> Scene: ...
def scene_from_toml(text: str, set: Overrides = None, name: str = "<string>") -> Scene: ...
def toss(
    scene: SceneArg,
    n: Optional[Count] = None,
    seed: int = 1,
    threads: int = 0,
    fidelity: Optional[str] = None,
    target_halfwidth: Optional[float] = None,
    progress: Progress = None,
) -> Result: ...
def toss_one(
    scene: Scene, index: int, seed: int = 1, fidelity: Optional[str] = None, trace: bool = True
) -> dict[str, Any]: ...
class ShowPage:
    html: str
    def _repr_html_(self) -> str: ...
    def save(self, path: str) -> None: ...

def show(scene: Scene, toss: Optional[int] = None, seed: int = 1, fidelity: Optional[str] = None) -> ShowPage: ...
def sweep(
    scene: SceneArg,
    key: str,
    values: Union[str, Iterable[float]],
    n: Count,
    seed: int = 1,
    threads: int = 0,
    fidelity: Optional[str] = None,
    template: str = "{}",
    scale: float = 1.0,
    shift: float = 0.0,
    progress: Progress = None,
) -> Sweep: ...
def sweep_file(
    path: str,
    n: Optional[Count] = None,
    seed: Optional[int] = None,
    threads: int = 0,
    fidelity: Optional[str] = None,
    progress: Progress = None,
) -> Sweep: ...
def fit(
    scene: Union[Scene, str, Sequence[Union[Scene, str]]],
    data: Union[str, Mapping[int, int], Sequence[Union[str, Mapping[int, int]]]],
    params: Union[Mapping[str, Tuple[float, float]], Sequence[str]],
    n: Count = 0,
    rounds: int = 3,
    seed: int = 1,
    threads: int = 0,
    fidelity: Optional[str] = None,
    progress: Progress = None,
) -> dict[str, Any]: ...
def power(
    scene: SceneArg,
    *,
    against: Optional[SceneArg] = None,
    detect_bias: Optional[float] = None,
    n: Count = 100000,
    alpha: float = 0.05,
    power: float = 0.8,
    replicates: int = 4000,
    bootstrap: int = 1000,
    seed: int = 1,
    threads: int = 0,
    fidelity: Optional[str] = None,
    progress: Progress = None,
) -> dict[str, Any]: ...  # exactly `dicesim power --json`'s object
