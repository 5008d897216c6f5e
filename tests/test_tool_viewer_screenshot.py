"""tools/viewer_screenshot.py's command line (the screenshot itself: tests/test_viewer_browser.py): --help shows
the usage, and gente-view's arguments must follow --."""

import pytest


@pytest.fixture(scope="module")
def tool(load_file):
    return load_file("tools/viewer_screenshot.py")


def test_help_shows_the_usage(tool, capsys):
    with pytest.raises(SystemExit) as stop:
        tool.main(["--help"])
    assert stop.value.code == 0 and "out -- GENTE_VIEW_ARGS" in capsys.readouterr().out


def test_without_gente_views_arguments_is_a_usage_error(tool, capsys):
    with pytest.raises(SystemExit) as stop:
        tool.main(["shot.png", "--wait", "5"])
    assert stop.value.code == 2 and "give gente-view's arguments after --" in capsys.readouterr().err
