"""The native module (Rust, pyo3): the functions `proving_ground` wraps."""

from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

Source = Union[str, Tuple[str, str]]

class ProvingGroundError(Exception):
    """An input that cannot be used or a run that could not be made."""

def validate(design: Source, scenario: Optional[Source], options: str) -> str: ...
def reach(
    designs: Sequence[Source],
    scenario: Source,
    ik_seeds: int,
    seed: int,
    search_boxes: int,
    threads: Optional[int],
) -> Dict[str, Any]: ...
def loss_and_grad(
    designs: Sequence[Source],
    scenario: Source,
    samples: Optional[Sequence[Tuple[int, int]]],
    q: np.ndarray,
) -> Dict[str, np.ndarray]: ...
def modular6(index: int) -> str: ...
def modular6_ids() -> List[str]: ...
def sweep_search_boxes() -> int: ...
def generate(generator: str, seed: Optional[int], task: Optional[int], count: Optional[int]) -> str: ...
