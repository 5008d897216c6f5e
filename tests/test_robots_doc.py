"""docs/robots.md's tables against the shipped MJCF files: each robot's DoF and total mass (its heading), the mass
of each body (the body table) and every column of the joint table. Plain MuJoCo, no Warp."""

import re
from pathlib import Path

import mujoco
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = (ROOT / "docs" / "robots.md").read_text()
GROUPS = {"s": ("left", "right"), "L": ("FL", "FR", "RL", "RR")}
AXES = {"x": [1.0, 0.0, 0.0], "y": [0.0, 1.0, 0.0], "z": [0.0, 0.0, 1.0]}


def section(robot: str) -> str:
    return re.search(rf"^## {robot} .*?(?=^## |\Z)", DOC, re.S | re.M).group(0)


def table_rows(text: str, first_header: str) -> list[list[str]]:
    """The body rows of the markdown table whose header starts with ``| first_header |``."""
    lines = text[text.index(f"| {first_header} |"):].splitlines()
    rows = []
    for line in lines[2:]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip("|").split("|")])
    return rows


def number(text: str) -> float:
    return float(text.replace("\u2212", "-"))


def model(robot: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(ROOT / "legged_gente" / "resources" / "robots" / robot / f"{robot}.xml"))


@pytest.mark.parametrize("robot", ["gente_biped", "gente_quadruped"])
def test_heading_dof_and_mass(robot):
    dof, mass = re.search(rf"^## {robot} \((\d+) DoF, ([\d.]+) kg\)", DOC, re.M).groups()
    m = model(robot)
    assert m.nu == int(dof)
    assert mujoco.mj_getTotalmass(m) == pytest.approx(float(mass), abs=0.05)


@pytest.mark.parametrize("robot", ["gente_biped", "gente_quadruped"])
def test_body_table_masses(robot):
    m = model(robot)
    names = [m.body(b).name for b in range(1, m.nbody)]
    listed = 0
    for cells in table_rows(section(robot), "body"):
        label = re.match(r"([a-z ]+?)\s*(?:\(welded\))?\s*(?:\(\u00d7(\d)\))?$", cells[0])
        key, count = label.group(1).replace(" ", "_"), int(label.group(2) or 1)
        bodies = [n for n in names if n == key or n.endswith("_" + key)]
        assert len(bodies) == count, (cells[0], bodies)
        for body in bodies:
            assert m.body(body).mass[0] == pytest.approx(number(cells[1])), body
        listed += count
    assert listed == len(names)  # the table lists every body


@pytest.mark.parametrize("robot", ["gente_biped", "gente_quadruped"])
def test_joint_table(robot):
    m = model(robot)
    rows = table_rows(section(robot), "joint")
    assert sum(len(GROUPS[re.search(r"\{(\w)\}", r[0]).group(1)]) for r in rows) == m.njnt - 1  # every joint
    for cells in rows:
        pattern = re.search(r"`([^`]+)`", cells[0]).group(1)
        group = re.search(r"\{(\w)\}", pattern).group(1)
        low, high = (number(x) for x in cells[2].split("\u2026"))
        kp, kv = (number(x) for x in cells[6].split("/"))
        for prefix in GROUPS[group]:
            name = pattern.replace("{" + group + "}", prefix)
            j, act = m.joint(name), m.actuator(name)
            dof = m.jnt_dofadr[j.id]
            assert m.jnt_axis[j.id].tolist() == AXES[cells[1]], name
            assert m.jnt_range[j.id].tolist() == pytest.approx([low, high]), name
            assert m.jnt_actfrcrange[j.id].tolist() == pytest.approx([-number(cells[3]), number(cells[3])]), name
            assert m.dof_armature[dof] == pytest.approx(number(cells[4])), name
            assert m.dof_damping[dof] == pytest.approx(number(cells[5])), name
            assert (m.actuator_gainprm[act.id, 0], -m.actuator_biasprm[act.id, 2]) == pytest.approx((kp, kv)), name
