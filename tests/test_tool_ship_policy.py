"""tools/ship_policy.py: a run's checkpoint becomes a task's shipped policy; a wrong task, checkpoint or run folder
is one line naming the fix (exit 2), and nothing is written."""

import json

import pytest
import torch

from legged_gente.utils import checkpoints


@pytest.fixture()
def tool(load_file, tmp_path, monkeypatch):
    monkeypatch.setattr(checkpoints, "policies_root", lambda: tmp_path / "policies")  # never the package's
    return load_file("tools/ship_policy.py")


def run_folder(path, task="gente_biped_flat"):
    path.mkdir()
    actor = {"mlp.0.weight": torch.zeros(4, 3), "mlp.2.weight": torch.zeros(2, 4),
             "distribution.std_param": torch.ones(2)}
    torch.save({"actor_state_dict": actor, "iter": 7, "infos": {"task": task}}, path / "model_7.pt")
    (path / "config.json").write_text(json.dumps({"task": task}))
    return path / "model_7.pt"


def test_ships_the_actor_and_the_note(tool, tmp_path, capsys):
    tool.main([str(run_folder(tmp_path / "run")), "--task", "gente_biped_flat", "--note", "a test"])
    folder = tmp_path / "policies" / "gente_biped_flat"
    assert capsys.readouterr().out.strip() == f"wrote {folder}"
    assert json.loads((folder / "config.json").read_text())["note"] == "a test"
    assert checkpoints.load_checkpoint(folder / "model.pt")["infos"] == {"task": "gente_biped_flat", "num_actions": 2}


@pytest.mark.parametrize("case, message", [
    ("no file", "checkpoint {run}/model_3.pt: no such file."),
    ("unknown task", "unknown task 'gente_bipd'; registered tasks:"),
    ("other task", "is for gente_biped_flat, not gente_quadruped: ship it as --task gente_biped_flat"),
    ("no config", "config.json not found: a shipped policy needs its run's config.json"),
])
def test_a_wrong_checkpoint_or_task_is_one_line(tool, tmp_path, capsys, case, message):
    checkpoint = run_folder(tmp_path / "run")
    task = {"unknown task": "gente_bipd", "other task": "gente_quadruped"}.get(case, "gente_biped_flat")
    if case == "no file":
        checkpoint = checkpoint.with_name("model_3.pt")
    if case == "no config":
        (tmp_path / "run" / "config.json").unlink()
    with pytest.raises(SystemExit) as stop:
        tool.main([str(checkpoint), "--task", task, "--note", "x"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1 and err.startswith("ship_policy: error: "), err
    assert message.format(run=tmp_path / "run") in err, err
    assert not (tmp_path / "policies").exists()
