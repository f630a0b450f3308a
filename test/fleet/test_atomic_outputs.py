# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Every output whole or not at all, and writers that must not interleave locked (issue 36, item 4)."""
import json
import os
from pathlib import Path
import subprocess
import sys
import time

import pytest

from prsm_lube_ros.atomic_file import file_lock, save_figure, staged_folder, write_text_atomically

ROOT = Path(__file__).resolve().parents[2]


def under_file_size_limit(code, limit, cwd):
    """Run ``code`` in a Python whose files may grow to ``limit`` bytes (``ulimit -f``)."""
    return subprocess.run([sys.executable, '-c', 'import resource\n'
                           f'resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))\n' + code],
                          capture_output=True, text=True, cwd=cwd, timeout=120)


def test_json_over_the_file_size_limit_is_one_line_and_the_old_file_stays_whole(tmp_path):
    out = tmp_path / 'out.json'
    out.write_text(json.dumps({'runs': ['earlier']}))
    code = ('import sys\nfrom prsm_lube_ros.cli.common import write_json\nfrom prsm_lube_ros.errors import InputError\n'
            'try:\n    write_json(sys.argv[1], {"runs": ["x" * 100] * 1000})\n'
            'except InputError as exc:\n    print(exc, file=sys.stderr)\n    sys.exit(2)\n')
    result = subprocess.run([sys.executable, '-c', 'import resource\n'
                             'resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))\n' + code, str(out)],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2 and 'Traceback' not in result.stderr, result.stderr
    assert str(out) in result.stderr and len(result.stderr.strip().splitlines()) == 1
    assert json.loads(out.read_text()) == {'runs': ['earlier']}
    assert [p.name for p in tmp_path.iterdir()] == ['out.json']             # no temporary left


def test_a_text_write_that_fails_leaves_the_old_file_and_a_stream_target_is_written_directly(tmp_path):
    path = tmp_path / 'trend.md'
    path.write_text('old')

    class Broken(str):
        def encode(self, *args):
            raise OSError(28, 'No space left on device')
    with pytest.raises(OSError):
        write_text_atomically(path, Broken('new'))
    assert path.read_text() == 'old' and sorted(p.name for p in tmp_path.iterdir()) == ['trend.md']
    fifo = tmp_path / 'pipe'
    os.mkfifo(fifo)
    with pytest.raises(OSError):                    # nobody reads: refused at once, not a wait forever
        write_text_atomically(fifo, 'to nobody\n')
    reader = subprocess.Popen(['cat', str(fifo)], stdout=subprocess.PIPE)
    for _ in range(500):                            # until cat has opened its end
        try:
            write_text_atomically(fifo, 'through a pipe\n')
            break
        except OSError:
            time.sleep(0.01)
    assert reader.communicate(timeout=10)[0] == b'through a pipe\n'


def test_a_figure_that_fails_to_render_leaves_the_old_one(tmp_path):
    path = tmp_path / 'fig.png'
    path.write_bytes(b'old png')

    class Figure:
        def savefig(self, stream, format):
            stream.write(b'half a png')
            raise OSError(27, 'File too large')
    with pytest.raises(OSError):
        save_figure(Figure(), path)
    assert path.read_bytes() == b'old png' and len(list(tmp_path.iterdir())) == 1


def test_a_report_is_staged_and_moved_into_place_file_by_file(tmp_path):
    report = tmp_path / 'report'
    report.mkdir()
    (report / 'index.html').write_text('old page')
    (report / 'notes.txt').write_text('the user\'s')
    with pytest.raises(RuntimeError):
        with staged_folder(report) as staged:
            (staged / 'index.html').write_text('half a new page')
            raise RuntimeError('killed while writing')
    assert (report / 'index.html').read_text() == 'old page'
    with staged_folder(report) as staged:
        (staged / 'index.html').write_text('new page')
        (staged / 'figures').mkdir()
        (staged / 'figures' / 'a.png').write_bytes(b'png')
    assert (report / 'index.html').read_text() == 'new page' and (report / 'figures' / 'a.png').is_file()
    assert (report / 'notes.txt').read_text() == 'the user\'s'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['report']


def test_the_commit_lock_is_exclusive_across_processes(tmp_path):
    lock = tmp_path / '.lock'
    with file_lock(lock):
        other = subprocess.run([sys.executable, '-c', 'from pathlib import Path\n'
                                'from prsm_lube_ros.atomic_file import file_lock\n'
                                f'with file_lock(Path({str(lock)!r}), timeout=0.3):\n    pass\n'],
                               capture_output=True, text=True, timeout=60)
        assert other.returncode != 0 and 'held .lock' in other.stderr
    with file_lock(lock, timeout=0.3):
        pass
