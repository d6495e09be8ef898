"""Reference values from timor-python itself for tests/timor.rs: tool poses and collision geometry
placements of Timor assemblies at seeded random configurations.

Run with timor-python 1.1.1 installed (it brings pinocchio and hpp-fcl):
    python3 scripts/timor_reference.py > tests/fixtures/timor/reference.json
Offline, Timor needs its schema cache filled and its robot download guarded; the values do not
depend on either.
"""
import json
import sys
from pathlib import Path

import numpy as np
import hppfcl
import pinocchio as pin
from timor.Module import ModulesDB, ModuleAssembly

REPO = Path(__file__).resolve().parent.parent
SETS = REPO / "designs" / "timor"

ASSEMBLIES = [
    ("geometric_primitive_modules", ["base", "J2", "l_30", "J2", "i_30", "J2", "l_15", "J2", "eef"]),
    ("geometric_primitive_modules", ["base", "J2", "J2", "l_45", "J2", "i_15", "J2", "l_30", "J2", "J2", "eef"]),
    ("geometric_primitive_modules", ["base", "J1", "l_15", "J2", "i_45", "J1", "J2", "eef"]),
    ("IMPROV", ["1", "21", "4", "22", "5", "23", "12"]),
    ("IMPROV", ["1", "29", "14", "22", "15", "23", "16"]),
]


# Module sets and the most modules of their serial assemblies listed as design spaces.
SPACES = [("geometric_primitive_modules", 5), ("IMPROV", 5)]


def design_space(name, most):
    """Every module order Timor's from_serial_modules assembles into a robot: at least one joint,
    a tool connector (the one free connector, or the one of type eef among several), and where the
    set has eef connectors, an eef tool."""
    db = ModulesDB.from_name(name)
    ids = sorted(m.id for m in db)
    has_eef = any(c.type == "eef" for m in db for c in m.available_connectors.values())
    bases = [m.id for m in db if sum(c.type == "base" for c in m.available_connectors.values()) == 1]
    found = []
    stack = [[b] for b in bases]
    while stack:
        order = stack.pop()
        try:
            assembly = ModuleAssembly.from_serial_modules(db, order)
        except Exception:
            continue
        free = list(assembly.free_connectors.values())
        eef = [c for c in free if c.type == "eef"]
        if assembly.nJoints >= 1:
            if (len(free) == 1 and (not has_eef or free[0].type == "eef")) or (len(free) > 1 and len(eef) == 1):
                found.append(",".join(order))
        if len(order) < most:
            stack.extend(order + [m] for m in ids)
    return {"module_set": name, "most_modules": most, "orders": sorted(found)}


def _set_file(name):
    from timor.utilities.file_locations import get_module_db_files
    return Path(get_module_db_files(name))


def shape(geometry):
    g = geometry.geometry
    if isinstance(g, hppfcl.Box):
        return {"type": "box", "half_extents": [float(x) for x in g.halfSide]}
    if isinstance(g, hppfcl.Cylinder):
        return {"type": "cylinder", "radius": float(g.radius), "length": 2.0 * float(g.halfLength)}
    if isinstance(g, hppfcl.Sphere):
        return {"type": "sphere", "radius": float(g.radius)}
    return {"type": "mesh"}


def main():
    rng = np.random.default_rng(20261127)
    cases = []
    for set_name, order in ASSEMBLIES:
        # Timor's own copy of its sample sets: it wants the visual meshes too, not shipped here
        # (designs/timor holds the same modules.json files).
        db = ModulesDB.from_name(set_name)
        ours = (SETS / set_name / "modules.json").read_text()
        assert ours == _set_file(set_name).read_text(), f"designs/timor/{set_name} differs from Timor's copy"
        robot = ModuleAssembly.from_serial_modules(db, order).robot
        lower, upper = robot.joint_limits
        configurations = []
        for _ in range(4):
            q = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi))
            robot.update_configuration(q)
            # Computed here rather than read from Timor's cache: it leaves geometries on the
            # universe joint (the base's) unset.
            pin.forwardKinematics(robot.model, robot.data, q)
            pin.updateGeometryPlacements(robot.model, robot.data, robot.collision, robot.collision_data)
            geometries = []
            for k, obj in enumerate(robot.collision.geometryObjects):
                placement = robot.collision_data.oMg[k].homogeneous
                geometries.append({"name": obj.name, "pose": placement.tolist(), **shape(obj)})
            configurations.append({
                "q": q.tolist(),
                "tool": robot.fk(q).homogeneous.tolist(),
                "geometries": geometries,
            })
        cases.append({
            "module_set": set_name,
            "module_order": order,
            "joints": robot.joints,
            "configurations": configurations,
        })
    spaces = [design_space(name, n) for name, n in SPACES]
    json.dump({"source": "timor-python 1.1.1 (pinocchio, hpp-fcl), scripts/timor_reference.py", "cases": cases,
               "design_spaces": spaces}, sys.stdout, indent=1)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
