"""With --json, stdout holds the JSON alone (issue 34, item 13).

``--json`` with ``--plot`` printed "... plot written to ..." after the JSON on stdout, so that
``shapefmu identify r.csv --json --plot p.png | jq`` failed. Now the messages about files written go
to stderr whenever --json is given (``cli.arguments.say_written``, the one line recommend will use
too), and to stdout otherwise, as before. The JSON is read back by Python's own parser.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hostile_support import guarded

RECORDING = Path(__file__).resolve().parent / "data" / "recordings" / "ender3_resonances_x_20210821_152037.csv"
COMMANDS = {
    "profile": ["profile", "hanning", "--mode", "40:0.05", "--distance", "0.01"],
    "identify": ["identify", str(RECORDING)],
}


@pytest.mark.parametrize("command", COMMANDS)
def test_with_json_stdout_is_the_json_alone_and_the_plot_message_is_on_stderr(tmp_path, command):
    plot = tmp_path / "p.png"
    code, out, err = guarded([*COMMANDS[command], "--json", "--plot", plot], seconds=600)
    assert code == 0, err
    json.loads(out)  # the whole of stdout, nothing after it
    assert f"written to {plot}" in err and plot.is_file()


@pytest.mark.parametrize("command", COMMANDS)
def test_without_json_the_plot_message_stays_on_stdout(tmp_path, command):
    plot = tmp_path / "p.png"
    code, out, err = guarded([*COMMANDS[command], "--plot", plot], seconds=600)
    assert code == 0, err
    assert f"written to {plot}" in out and "written to" not in err
