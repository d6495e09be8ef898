from typing import Any, Dict, Iterable, List, Optional, Sequence, Union
import os

import numpy as np

class ProvingGroundError(Exception): ...

class Design:
    path: Optional[str]
    data: Optional[Dict[str, Any]]
    def __init__(self, source: Union[str, os.PathLike, Dict[str, Any]]) -> None: ...
    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "Design": ...
    @classmethod
    def from_dict(cls, data: Dict[str, Any]) -> "Design": ...
    @classmethod
    def from_dh(cls, rows: Any, mode: str = ..., name: str = ..., limits: Optional[Sequence[float]] = ...) -> "Design": ...

class Scenario:
    path: Optional[str]
    data: Optional[Dict[str, Any]]
    def __init__(self, source: Union[str, os.PathLike, Dict[str, Any]]) -> None: ...
    @classmethod
    def load(cls, path: Union[str, os.PathLike]) -> "Scenario": ...
    @classmethod
    def from_dict(cls, data: Dict[str, Any]) -> "Scenario": ...
    @classmethod
    def generate(cls, generator: str, seed: Optional[int] = ..., task: Optional[int] = ..., count: Optional[int] = ...) -> "Scenario": ...

DesignLike = Union[Design, Dict[str, Any], str, os.PathLike]
ScenarioLike = Union[Scenario, Dict[str, Any], str, os.PathLike]

def validate(design: DesignLike, scenario: Optional[ScenarioLike] = ..., **options: Any) -> Dict[str, Any]: ...
def reach(
    designs: Union[Sequence[DesignLike], np.ndarray],
    scenario: ScenarioLike,
    ik_seeds: int = ...,
    seed: int = ...,
    search_boxes: Optional[int] = ...,
    threads: Optional[int] = ...,
) -> Dict[str, Any]: ...
def loss_and_grad(
    designs: Union[DesignLike, Sequence[DesignLike]],
    scenario: ScenarioLike,
    q: Any,
    samples: Optional[Iterable[Sequence[int]]] = ...,
) -> Dict[str, np.ndarray]: ...
def catalog(name: str = ...) -> List[str]: ...
def catalog_design(index: int) -> Design: ...
