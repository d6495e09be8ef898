"""proving-ground from Python, in process: validate, score and differentiate robot designs.

The functions here call the same library as ``validate-design``: a report from :func:`validate`
is the command's ``--json`` report, the numbers from :func:`reach` are the records ``sweep``
writes. Long work runs with the GIL released. Every bad input raises
:class:`ProvingGroundError` with the command line's message (file, field or line, what was
expected).
"""

from __future__ import annotations

import json
import os
import sys
from typing import Any, Dict, Iterable, List, Optional, Sequence, Union

import numpy as np


def _use_mujoco_package() -> None:
    """Points the engines at the MuJoCo library of the ``mujoco`` package (a pinned dependency),
    unless ``MUJOCO_LIBRARY`` already names one: the installed module then needs nothing from the
    checkout it was built in. The library's version is checked at its first use."""
    if "MUJOCO_LIBRARY" in os.environ:
        return
    import importlib.util

    spec = importlib.util.find_spec("mujoco")
    for folder in (spec.submodule_search_locations or []) if spec else []:
        names = sorted(n for n in os.listdir(folder) if n.startswith("libmujoco.so."))
        if names:
            os.environ["MUJOCO_LIBRARY"] = os.path.join(folder, names[-1])
            return


_use_mujoco_package()

# MuJoCo is loaded at its first use, not with the module (as in the `validate-design` binary):
# its symbols are bound lazily, which Python's default RTLD_NOW for extension modules forbids.
_flags = sys.getdlopenflags()
sys.setdlopenflags((_flags & ~os.RTLD_NOW) | os.RTLD_LAZY)
try:
    from . import _proving_ground as _native
    from ._proving_ground import ProvingGroundError
finally:
    sys.setdlopenflags(_flags)

__all__ = [
    "Design",
    "ProvingGroundError",
    "Scenario",
    "catalog",
    "catalog_design",
    "loss_and_grad",
    "reach",
    "validate",
]


class _Input:
    """A file, read when it is used, or the JSON object such a file holds."""

    _default_name = "input"

    def __init__(self, source: Union[str, os.PathLike, Dict[str, Any]]):
        if isinstance(source, dict):
            self.path: Optional[str] = None
            self.data: Optional[Dict[str, Any]] = source
        else:
            self.path = os.fspath(source)
            self.data = None

    @classmethod
    def load(cls, path: Union[str, os.PathLike]):
        """The file at ``path``, read when it is used."""
        return cls(path)

    @classmethod
    def from_dict(cls, data: Dict[str, Any]):
        """The JSON object of such a file."""
        return cls(dict(data))

    def _name(self) -> str:
        return str(self.data.get("name", self._default_name)) if self.data is not None else str(self.path)

    def _source(self) -> Any:
        """What the native module takes: the path, or `(name.json, JSON text)`."""
        if self.data is not None:
            return (f"{self._name()}.json", json.dumps(self.data, allow_nan=False, indent=1))
        return self.path

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._name()!r})"


class Design(_Input):
    """A design (the JSON a design file holds), or a robot file (design JSON, URDF, MJCF)."""

    _default_name = "design"

    @classmethod
    def from_dh(
        cls,
        rows: Any,
        mode: str = "free",
        name: str = "design",
        limits: Optional[Sequence[float]] = None,
    ) -> "Design":
        """A free or economic design from standard DH rows ``(d, a, alpha)``, one per joint."""
        array = np.asarray(rows, dtype=float)
        if array.ndim != 2 or array.shape[1] != 3:
            raise ProvingGroundError(f"DH rows: shape {array.shape}; expected (joints, 3): d, a, alpha per joint")
        joints = []
        for d, a, alpha in array.tolist():
            joint: Dict[str, Any] = {"d": d, "a": a, "alpha": alpha}
            if limits is not None:
                joint["limits"] = list(limits)
            joints.append(joint)
        return cls({"name": name, "mode": mode, "joints": joints})


class Scenario(_Input):
    """A scenario (goals, obstacles, floor): a file, the JSON of one, or a generator's."""

    _default_name = "scenario"

    @classmethod
    def generate(
        cls,
        generator: str,
        seed: Optional[int] = None,
        task: Optional[int] = None,
        count: Optional[int] = None,
    ) -> "Scenario":
        """What ``validate-design generate`` writes: ``cluttered`` (one ``task``), ``workspace``
        (``count`` poses) or ``course``; ``seed`` defaults to the generator's."""
        return cls(json.loads(_native.generate(generator, seed, task, count)))


def _source(value: Any, kind: type) -> Any:
    """A design or scenario (the object, a dict or a path) as the native module takes it."""
    if isinstance(value, kind):
        return value._source()
    if isinstance(value, (dict, str, os.PathLike)):
        return kind(value)._source()
    raise ProvingGroundError(f"a {kind.__name__.lower()} is a {kind.__name__}, a dict or a path; got {type(value).__name__}")


def validate(design: Any, scenario: Any = None, **options: Any) -> Dict[str, Any]:
    """The report ``validate-design DESIGN --json`` writes, as a dict.

    ``design``: a :class:`Design`, a design dict, or a path (design JSON, URDF, MJCF).
    ``scenario``: a :class:`Scenario`, a dict, a path, or ``None`` for the default course.
    ``options``: named as on the command line with ``_`` for ``-`` (``engines="mujoco"``,
    ``seed=1``, ``ik_seeds=8``, ``search_boxes``, ``tolerance="z_symmetric"``, ``margin``,
    ``contact_depth``, ``planner``, ``plan_budget``, ``reach_only=True``, ``srdf``, ``strict``,
    ``mujoco_checks``, ``base``, ``tip``, ``package_path``). Ctrl-C stops the run at the next
    goal (or within the planner's search) and raises ``KeyboardInterrupt``.
    """
    options = {k: os.fspath(v) if isinstance(v, os.PathLike) else v for k, v in options.items()}
    return json.loads(_native.validate(_source(design, Design), None if scenario is None else _source(scenario, Scenario), json.dumps(options)))


def reach(
    designs: Any,
    scenario: Any,
    ik_seeds: int = 4,
    seed: int = 0,
    search_boxes: Optional[int] = None,
    threads: Optional[int] = None,
) -> Dict[str, np.ndarray]:
    """The paper's reach-only metric of each design on ``scenario``, as ``sweep`` computes it.

    ``designs``: a list of designs (:class:`Design`, dicts or paths), or a float array of DH
    rows of shape ``(designs, joints, 3)`` (free designs). Returns NumPy arrays, one entry per
    design: ``goals``, ``solved``, ``proven_unreachable``, ``undecided``, ``task_solved``,
    ``task_loss`` (NaN where a goal has no configuration), ``hardware_cost``,
    ``position_error_mm``; and ``records``, each design's ``sweep`` record as JSON. The results
    are the same for any ``threads``.
    """
    if isinstance(designs, np.ndarray) or (
        isinstance(designs, (list, tuple)) and designs and not isinstance(designs[0], (Design, dict, str, os.PathLike))
    ):
        array = np.asarray(designs, dtype=float)
        if array.ndim != 3 or array.shape[2] != 3:
            raise ProvingGroundError(f"DH batch: shape {array.shape}; expected (designs, joints, 3)")
        designs = [Design.from_dh(rows, name=f"design-{k}") for k, rows in enumerate(array)]
    sources = [_source(d, Design) for d in designs]
    source = _source(scenario, Scenario)
    boxes = _native.sweep_search_boxes() if search_boxes is None else int(search_boxes)
    out = _native.reach(sources, source, int(ik_seeds), int(seed), boxes, threads)
    out["records"] = [json.loads(r) for r in out["records"]]
    return out


def loss_and_grad(
    designs: Any,
    scenario: Any,
    q: Any,
    samples: Optional[Iterable[Sequence[int]]] = None,
) -> Dict[str, np.ndarray]:
    """The paper's differentiable objective per sample and its gradients (the optimize stage's).

    Each sample is one design, one goal and one configuration: ``samples`` lists
    ``(design index, goal index)`` pairs (default: every goal of every design, design-major) and
    ``q`` holds one row of joint values per sample. Returns ``loss`` (``w_d d + w_col c_col``
    per sample), ``distance``, ``collision``, and ``grad_q``, ``grad_d``, ``grad_a`` of each
    sample's loss (rows per sample); and the paper's design objective, ``objective`` per design
    (per goal the least loss over its samples, summed, plus ``w_c`` times the hardware cost),
    ``chosen`` (the samples it takes) and its gradients ``objective_grad_d``,
    ``objective_grad_a`` (rows per design). The designs share one dof count and capsule
    structure.
    """
    if isinstance(designs, (Design, dict, str, os.PathLike)):
        designs = [designs]
    sources = [_source(d, Design) for d in designs]
    source = _source(scenario, Scenario)
    q = np.ascontiguousarray(q, dtype=float)
    pairs = None if samples is None else [(int(d), int(g)) for d, g in samples]
    if q.ndim == 1:
        q = q.reshape(1, -1)
    return _native.loss_and_grad(sources, source, pairs, q)


def catalog(name: str = "modular6") -> List[str]:
    """The ids of a design catalog's robots (``modular6``: the paper's 15 625 six-slot modular
    robots, in catalog order); :func:`catalog_design` gives one as a :class:`Design`."""
    if name != "modular6":
        raise ProvingGroundError(f"unknown catalog `{name}`; expected modular6")
    return list(_native.modular6_ids())


def catalog_design(index: int) -> Design:
    """The ``modular6`` catalog's robot number ``index`` (0 to 15 624) as a design."""
    return Design.from_dict(json.loads(_native.modular6(int(index))))
