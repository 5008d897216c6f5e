"""gente-generate refuses bad input with one line and exit status 2, before any model is asked: a flag that its other
flags would silently ignore, a --base-url that is not an http(s) address; and a tile the planner cannot lay out."""

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
    *[(["--text", "a lake", "--backend", "openai", "--base-url", url, "--model", "m"],
       f"--base-url {url}: not an http:// or https:// address with a host; give the server's API address, e.g. "
       f"http://localhost:8000/v1.") for url in ("file:///tmp/fs", "data:,{}", "localhost:8000/v1", "http:///v1", "http://[::1/v1")],
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


def test_a_tile_the_planner_cannot_lay_out_is_bad_input(capsys, tmp_path):
    """The planner asks no model: its refusal is of the text and the tile, exit 2 (1 is a server or model that
    failed). The stairs recipe rises 0.12 m every 0.35 m, beyond the 10 m height bound over a 200 m tile."""
    assert generate_script.main(["--text", "stairs", "--size", "200", "--resolution", "1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gente-generate: error: planner cue 'stairs' does not fit on a 200 m x 200 m tile: ask for a "
                          "smaller tile") and "Traceback" not in err and not (tmp_path / "o").exists()


def test_generating_into_a_folder_that_holds_a_terrain_says_it_was_replaced(tmp_path, capsys):
    out = tmp_path / "creek"
    assert generate_script.main(["--text", "a muddy field", "--size", "4", "--out", str(out)]) == 0
    assert "replaced" not in capsys.readouterr().err
    assert generate_script.main(["--text", "a muddy field", "--size", "4", "--out", str(out)]) == 0
    assert "replaced" not in capsys.readouterr().err  # the same terrain again: nothing replaced
    assert generate_script.main(["--text", "a river", "--size", "4", "--out", str(out)]) == 0
    assert f"note: replaced the terrain {out} held" in capsys.readouterr().err
