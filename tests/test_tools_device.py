"""tools/diagnose_divergence.py and tools/trace_failures.py: a --device that is not there is a one-line usage
error naming the devices to use, before anything is built (it was Warp's traceback once the env was made)."""

import sys

import pytest


@pytest.mark.parametrize("path", ["tools/diagnose_divergence.py", "tools/trace_failures.py"])
def test_a_missing_gpu_is_a_one_line_error(load_file, monkeypatch, capsys, path):
    tool = load_file(path)
    monkeypatch.setattr(sys, "argv", [path, "--task", "gente_biped", "--pretrained", "--benchmark", "flat",
                                      "--robots_per_terrain", "1", "--episode_s", "4", "--device", "cuda:99"])
    with pytest.raises(SystemExit) as stop:
        tool.main()
    assert stop.value.code == 2 and "--device cuda:99" in capsys.readouterr().err.strip().splitlines()[-1]
