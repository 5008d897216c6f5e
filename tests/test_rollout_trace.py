"""tools/rollout_trace.py: a short record on the CPU, and its comparison's verdicts (a NaN in the same place is
equal; one changed value, or a missing array, is a difference and exits with 1)."""

import numpy as np
import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/rollout_trace.py")


def test_compare_tells_equal_from_different(tool, tmp_path, capsys):
    a = {"t/obs": np.array([[1.0, np.nan], [3.0, 4.0]], np.float32), "t/qpos": np.zeros((2, 3), np.float32)}
    np.savez(tmp_path / "a.npz", **a)
    np.savez(tmp_path / "same.npz", **{k: v.copy() for k, v in a.items()})
    changed = {k: v.copy() for k, v in a.items()}
    changed["t/obs"][1, 1] = np.nextafter(np.float32(4.0), np.float32(5.0))  # one ulp
    np.savez(tmp_path / "changed.npz", **changed)
    np.savez(tmp_path / "missing.npz", **{"t/obs": a["t/obs"]})
    assert tool.compare(str(tmp_path / "a.npz"), str(tmp_path / "same.npz"))
    assert not tool.compare(str(tmp_path / "a.npz"), str(tmp_path / "changed.npz"))
    assert "t/obs: DIFFERENT, max |difference| 4.77e-07" in capsys.readouterr().out
    assert not tool.compare(str(tmp_path / "a.npz"), str(tmp_path / "missing.npz"))
    with pytest.raises(SystemExit) as info:
        tool.main(["compare", str(tmp_path / "a.npz"), str(tmp_path / "changed.npz")])
    assert info.value.code == 1


def test_two_records_of_the_same_code_are_bitwise_equal(tool, tmp_path, capsys):
    """The rollout is seeded: recorded twice, it is the same to the bit; 0.1 s episodes are 5 steps of 0.02 s, so in
    8 steps each robot resets once (the post-reset forward runs)."""
    for name in ("one", "two"):
        tool.main(["record", str(tmp_path / f"{name}.npz"), "--tasks", "gente_biped", "--num_envs", "2",
                   "--steps", "8", "--episode_s", "0.1"])
    assert "gente_biped: 8 steps of 2 robots, 2 resets" in capsys.readouterr().out
    assert tool.compare(str(tmp_path / "one.npz"), str(tmp_path / "two.npz"))
    assert sorted(np.load(tmp_path / "one.npz").files) == ["gente_biped/field_obs", "gente_biped/obs",
                                                           "gente_biped/qpos"]
