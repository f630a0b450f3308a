# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""JSON output: compact and streamed by default, indented on request, the same document either way."""
import json
import math
from pathlib import Path
import subprocess
import sys

import pytest

from prsm_lube_ros.cli import main
from prsm_lube_ros.cli.common import HiddenBar, json_pieces, progress_bar, write_json

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / 'scripts'))
from assess_reference import CASES  # noqa: E402  (the reference cases' recordings and calibrations)

DOCUMENT = {'runs': [{'theta_oil': 0.9, 'sigma': math.nan, 'peaks': [{'order': 6.25, 'component': 'screw'}]},
                     {'theta_oil': None, 'reason': 'axial load 0.2 N < 5 N', 'ok': True}],
            'windows': [], 'calibration': {'band': '0.5-1600 Hz', 'flags': ['a', 'b']}, 'runs_flagged': 0,
            'inf': [math.inf, -math.inf, 1e308], 'note': 'théta "quoted"\n'}
EXPECTED = json.loads(json.dumps(DOCUMENT).replace('NaN', 'null').replace('-Infinity', 'null')
                      .replace('Infinity', 'null'))


@pytest.mark.parametrize('indent', [None, 0, 1, 4])
def test_compact_and_indented_json_hold_the_same_document(indent, tmp_path):
    path = tmp_path / 'out.json'
    write_json(path, DOCUMENT, indent=indent)
    text = path.read_text()
    assert json.loads(text) == EXPECTED
    assert ('\n' not in text and ': ' not in text.replace('"axial load 0.2 N < 5 N"', '')) == (indent is None)


def test_compact_json_comes_in_pieces_one_per_top_level_item():
    pieces = list(json_pieces({'windows': [{'k': k} for k in range(1000)], 'runs': []}))
    assert len(pieces) > 1000 and max(len(p) for p in pieces) < 20
    assert json.loads(''.join(pieces)) == {'windows': [{'k': k} for k in range(1000)], 'runs': []}
    assert ''.join(json_pieces([1, math.nan])) == '[1,null]'


def test_assess_writes_compact_json_and_indents_it_on_request(tmp_path, capsys):
    recording, calibration, extra = CASES['sim_surface_defect']
    outputs = {}
    for indent in (None, 2):
        out = tmp_path / f'{indent}.json'
        argv = ['assess', str(recording), '--calibration', str(calibration), '--json', str(out), *extra]
        assert main(argv + ([] if indent is None else ['--indent', str(indent)])) == 0
        outputs[indent] = out.read_text()
    assert outputs[None].count('\n') == 0 and outputs[2].count('\n') > 100 and '\n    "' in outputs[2]
    assert json.loads(outputs[None]) == json.loads(outputs[2])
    assert main(['assess', str(recording), '--calibration', str(calibration), '--json', str(tmp_path / 'x.json'),
                 '--indent', '-1']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith('prsm-lube assess: error: --indent -1') and not (tmp_path / 'x.json').exists()


def test_a_bar_nobody_sees_imports_no_tqdm_and_counts():
    code = ('import sys\nfrom prsm_lube_ros.cli.common import progress_bar\nbar = progress_bar(10, "x")\n'
            'bar.update(3)\nbar.update(2)\nbar.close()\nprint(type(bar).__name__, bar.n, "tqdm" in sys.modules)')
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, stdin=subprocess.DEVNULL)
    assert result.stdout.split() == ['HiddenBar', '5', 'False'], result.stderr
    assert isinstance(progress_bar(3, 'y', unit='recording'), HiddenBar)     # pytest's stderr is no terminal
