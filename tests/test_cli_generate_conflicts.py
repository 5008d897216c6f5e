"""gente-generate refuses a flag that its other flags would silently ignore (one line, exit 2, before any model is
asked)."""

import pytest

from legged_gente.scripts import generate as generate_script

OPENAI = ["--backend", "openai", "--base-url", "http://localhost:1/v1", "--model", "m"]


@pytest.mark.parametrize("argv, message", [
    (["--text", "a lake", "--vision-model", "v"], "--base-url/--model/--vision-model/--two-phase/--toolset are for "
                                                  "--backend openai."),
    (["--text", "a lake", *OPENAI, "--two-phase"], "--two-phase describes the --image first; give --image or "
                                                   "leave out --two-phase."),
    (["--text", "a lake", *OPENAI, "--vision-model", "v"], "--vision-model describes the image in --two-phase; add "
                                                           "--two-phase (and --image) or leave it out."),
])
def test_flags_that_would_be_ignored_are_refused(capsys, monkeypatch, tmp_path, argv, message):
    def never(*args, **kwargs):
        raise AssertionError("a model was asked")

    monkeypatch.setattr(generate_script, "generate_spec", never)
    with pytest.raises(SystemExit) as exit_info:
        generate_script.main([*argv, "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2 and "Traceback" not in err
    assert err.strip().splitlines()[-1] == f"gente-generate: error: {message}"
