"""tools/viewer_screenshot.py without what it needs (Selenium, Debian's chromium and chromium-driver): a one-line
usage error naming the install, before gente-view is started (it used to start gente-view, then fail with a
traceback)."""

import importlib.util

import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/viewer_screenshot.py")


@pytest.fixture
def no_server(tool, monkeypatch):
    def popen(*args, **kwargs):
        raise AssertionError("gente-view started although the screenshot cannot be taken")

    monkeypatch.setattr(tool.subprocess, "Popen", popen)


def test_without_selenium_is_a_one_line_error(tool, no_server, monkeypatch, capsys):
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "selenium" else find_spec(name, *a))
    with pytest.raises(SystemExit) as stop:
        tool.main(["shot.png", "--", "--task", "gente_biped"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert stop.value.code == 2 and "Selenium" in err and 'pip install -e ".[browser]"' in err


def test_without_chromium_is_a_one_line_error(tool, no_server, monkeypatch, capsys, tmp_path):
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: object() if name == "selenium" else find_spec(name, *a))
    monkeypatch.setattr(tool, "CHROMIUM", str(tmp_path / "chromium"))
    with pytest.raises(SystemExit) as stop:
        tool.main(["shot.png", "--", "--task", "gente_biped"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert stop.value.code == 2 and str(tmp_path / "chromium") in err and "apt-get install" in err
