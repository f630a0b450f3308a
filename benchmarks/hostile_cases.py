# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The hostile kinds of ``fuzz_recordings.py --hostile``: files, links and writers a user or a request can aim at us.

Each case builds its inputs in a fresh folder and returns ``(outcome, detail)``;
outcomes are ``refused`` (one line naming the input, the expected answer),
``ok`` (what the case must do happened: writers consistent, old output whole)
and the failures ``traceback``, ``escape`` (a file outside the allowed root
was read, or a refusal repeats what the file holds), ``silent`` (accepted
what must be refused: a truncated calibration loaded), ``damaged_output``
(an earlier output not whole, or a temporary left), ``unnamed_refusal``,
``wedged`` (a request that did not return, or a service that did not answer
the next one) and ``memory``.  Kinds:

* ``special_file``: a FIFO, ``/dev/zero``, ``/dev/urandom``, a socket or
  ``/dev/stdin`` (a pipe holding 50 MB) as a recording, a bag's storage file,
  its ``metadata.yaml`` or a calibration file;
* ``symlink``: a bag folder's storage file or ``metadata.yaml`` linked to a
  recording or a secret outside the allowed root, read as the calibrate
  service reads (``recordings_dir``) and as the command line does;
* ``size_bound``: a 100 MB ``metadata.yaml``, a 100 MB calibration file and
  a history Parquet file of 0.5 MB whose footer holds 300 million rows;
* ``truncation``: a freshly written calibration file cut at a random byte;
* ``concurrent_writers``: 4 processes committing one recording to a history
  under two actuator ids at the same moment;
* ``full_disk``: ``--json``, a calibration file and a history commit under
  ``ulimit -f`` (a few kB), an earlier output in place;
* ``wedged_service``: the calibrate service's request path
  (:func:`~prsm_lube_ros.nodes.calibration_request.calibrate_from_request`)
  given a FIFO storage file, then a valid request.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
import random
import shutil
import socket
import subprocess
import sys
import threading

KINDS = ('special_file', 'symlink', 'size_bound', 'truncation', 'concurrent_writers', 'full_disk', 'wedged_service')
SECRET = 'root:x:0:0:hostile-secret-line:/root:/bin/bash\n'
#: s a single request may take before it counts as wedged
WEDGE_SECONDS = 20.0


def _refusal(text: str, named: str, secret: str = '') -> tuple[str, str]:
    if '\n' in text:
        return 'traceback', f'multi-line refusal: {text[:200]!r}'
    if secret and secret.strip() in text or 'hostile-secret' in text:
        return 'escape', f'refusal repeats the file\'s content: {text[:200]}'
    if named not in text:
        return 'unnamed_refusal', text[:200]
    return 'refused', ''


def _bag(work: Path, seeds: dict, name: str = 'bag') -> Path:
    target = work / name
    shutil.copytree(seeds['bag'], target)
    return target


def _refused(action, named: str, secret: str = '') -> tuple[str, str]:
    """Run ``action()``: it must raise one InputError line naming ``named``, within WEDGE_SECONDS."""
    from prsm_lube_ros.errors import InputError
    box: dict = {}

    def run():
        try:
            box['result'] = action()
        except BaseException as exc:    # judged below
            box['error'] = exc
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(WEDGE_SECONDS)
    if thread.is_alive():
        return 'wedged', f'no answer after {WEDGE_SECONDS:g} s'
    error = box.get('error')
    if error is None:
        return 'silent', 'accepted'
    if isinstance(error, MemoryError):
        return 'memory', 'MemoryError'
    if not isinstance(error, InputError):
        return 'traceback', f'{type(error).__name__}: {error}'[:300]
    return _refusal(str(error), named, secret)


def special_file(work: Path, seeds: dict, rng: random.Random) -> tuple[str, str]:
    """One special file in one place a file is read from."""
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    from prsm_lube_ros.recording.reader import open_recording
    what = rng.choice(['fifo', '/dev/zero', '/dev/urandom', 'socket', 'stdin'])
    where = rng.choice(['recording', 'storage', 'metadata', 'calibration'])
    if what == 'stdin':
        return _stdin_case(where, seeds)
    bag = _bag(work, seeds)
    target = {'recording': work / 'special.mcap', 'storage': next(bag.glob('*.mcap')),
              'metadata': bag / 'metadata.yaml', 'calibration': work / 'calibration.yaml'}[where]
    target.unlink(missing_ok=True)
    keep = None
    if what == 'fifo':
        os.mkfifo(target)
    elif what == 'socket':
        keep = socket.socket(socket.AF_UNIX)
        keep.bind(str(target))
    else:
        target.symlink_to(what)
    try:
        if where == 'calibration':
            return _refused(lambda: load_calibration(target), str(target))
        opened = target if where == 'recording' else bag
        return _refused(lambda: open_recording(opened, root='/' if what.startswith('/dev') else None), str(opened))
    finally:
        if keep is not None:
            keep.close()


def _stdin_case(where: str, seeds: dict) -> tuple[str, str]:
    """``--calibration /dev/stdin`` (or a recording): 50 MB in a pipe, refused before a byte is read."""
    code = ('import sys\nfrom prsm_lube_ros.errors import InputError\n'
            'from prsm_lube_ros.estimation.calibration_file import load_calibration\n'
            'from prsm_lube_ros.recording.reader import open_recording\n'
            f'try:\n    (load_calibration if {where == "calibration"} else open_recording)("/dev/stdin")\n'
            '    print("accepted")\nexcept InputError as exc:\n    print(exc)\n')
    try:
        result = subprocess.run([sys.executable, '-c', code], input=b'x' * (50 << 20), capture_output=True,
                                timeout=WEDGE_SECONDS)
    except subprocess.TimeoutExpired:
        return 'wedged', '/dev/stdin'
    except BrokenPipeError:    # refused before reading: the pipe closed with 50 MB unread (the answer wanted)
        return 'refused', ''
    text = result.stdout.decode().strip()
    if result.returncode or 'Traceback' in result.stderr.decode():
        return 'traceback', result.stderr.decode()[-300:]
    return ('silent', text) if text == 'accepted' else _refusal(text, '/dev/stdin')


def symlink(work: Path, seeds: dict, rng: random.Random) -> tuple[str, str]:
    """A bag inside the allowed root whose storage file or metadata.yaml links out of it."""
    from prsm_lube_ros.recording.reader import open_recording
    root = work / 'recordings'
    root.mkdir()
    outside = _bag(work, seeds, 'outside')
    (work / 'passwd').write_text(SECRET)
    bag = _bag(root, seeds)
    which = rng.choice(['storage', 'metadata'])
    link = next(bag.glob('*.mcap')) if which == 'storage' else bag / 'metadata.yaml'
    link.unlink()
    link.symlink_to(rng.choice([work / 'passwd', next(outside.glob('*.mcap')) if which == 'storage'
                                else outside / 'metadata.yaml']))
    service = rng.random() < 0.5
    outcome, detail = _refused(lambda: open_recording(bag, root=root if service else None), str(bag), SECRET)
    if outcome == 'silent':
        return 'escape', f'{which} linked out of {"recordings_dir" if service else "the bag folder"} was read'
    return outcome, detail


def size_bound(work: Path, seeds: dict, rng: random.Random) -> tuple[str, str]:
    """A file whose size (or footer) alone would cost memory: refused before it is loaded."""
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    from prsm_lube_ros.recording.reader import open_recording
    which = rng.choice(['metadata', 'calibration', 'parquet'])
    if which == 'parquet':
        return _huge_parquet(work, seeds)
    bag = _bag(work, seeds)
    target = bag / 'metadata.yaml' if which == 'metadata' else work / 'calibration.yaml'
    with open(target, 'w') as stream:
        stream.write('rosbag2_bagfile_information:\n  topics: [\n')
        stream.truncate(100 << 20)            # 100 MB (sparse): only its size may be looked at
    if which == 'metadata':
        return _refused(lambda: open_recording(bag), str(target))
    return _refused(lambda: load_calibration(target), str(target))


def _huge_parquet(work: Path, seeds: dict) -> tuple[str, str]:
    from prsm_lube_ros.fleet.history import read_table
    file = work / 'history' / 'runs' / 'actuator=a' / f'{"0" * 16}.parquet'
    file.parent.mkdir(parents=True)
    shutil.copy(seeds['huge_parquet'], file)
    problems: list[str] = []
    table = read_table(work / 'history', on_problem=problems.append)
    if table.num_rows:
        return 'silent', f'{table.num_rows} rows loaded'
    return _refusal(problems[0], str(file)) if problems else ('silent', 'nothing said')


def truncation(work: Path, seeds: dict, rng: random.Random) -> tuple[str, str]:
    """A freshly written calibration file cut short: never loaded as an older format."""
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    data = Path(seeds['calibration']).read_bytes()
    path = work / 'cut.yaml'
    path.write_bytes(data[:rng.randrange(1, len(data))])
    return _refused(lambda: load_calibration(path), str(path))


def _commit(history: str, bag: str, actuator: str, barrier: str, writers: int) -> str:
    import time
    from prsm_lube_ros.fleet.history import add_assessment, content_hash
    from prsm_lube_ros.estimation.pipeline import RecordingAssessment

    def gather(staged):
        Path(barrier, str(os.getpid())).touch()
        deadline = time.monotonic() + 10
        while len(list(Path(barrier).iterdir())) < writers and time.monotonic() < deadline:
            time.sleep(0.001)
    try:
        add_assessment(history, RecordingAssessment(bag, [], []), actuator_id=actuator,
                       content=content_hash(bag), calibration='c0ffee', before_commit=gather)
        return ''
    except Exception as exc:      # judged by the caller
        return f'{type(exc).__name__}: {exc}'


def concurrent_writers(work: Path, seeds: dict, rng: random.Random) -> tuple[str, str]:
    """4 writers commit one recording under two actuator ids at once: one runs file, no error."""
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing
    bag = work / 'a.mcap'
    bag.write_bytes(rng.randbytes(64))
    (work / 'barrier').mkdir()
    with ProcessPoolExecutor(4, mp_context=multiprocessing.get_context('fork')) as pool:
        errors = [e for e in pool.map(_commit, [str(work / 'history')] * 4, [str(bag)] * 4,
                                      ['/left', '/right'] * 2, [str(work / 'barrier')] * 4, [4] * 4) if e]
    files = list((work / 'history' / 'runs').glob('actuator=*/*.parquet'))
    if errors or len(files) != 1:
        return 'damaged_output', f'{len(files)} runs files; {errors[:1]}'
    return 'ok', ''


def full_disk(work: Path, seeds: dict, rng: random.Random) -> tuple[str, str]:
    """An output written under ``ulimit -f``: one line, the earlier file whole, no temporary left."""
    which = rng.choice(['json', 'calibration', 'history'])
    out = work / 'out'
    out.mkdir()
    target = out / {'json': 'out.json', 'calibration': 'calib.yaml', 'history': 'history'}[which]
    if which == 'history':
        before = None
    elif which == 'json':
        target.write_text(json.dumps({'runs': ['earlier']}))
        before = target.read_bytes()
    else:
        shutil.copy(seeds['calibration'], target)
        before = target.read_bytes()
    code = {'json': 'from prsm_lube_ros.cli.common import write_json\n'
                    f'write_json({str(target)!r}, {{"runs": ["x" * 100] * 2000}})\n',
            'calibration': 'from prsm_lube_ros.estimation.calibration_file import load_calibration, save_calibration\n'
                           f'c = load_calibration({seeds["calibration"]!r})\n'
                           f'save_calibration(c, {str(target)!r})\n',
            'history': 'import datetime\nfrom prsm_lube_ros.fleet.history import add_assessment\n'
                       'from prsm_lube_ros.estimation.pipeline import RecordingAssessment\n'
                       f'add_assessment({str(target)!r}, RecordingAssessment("a", [], []), actuator_id="a", '
                       'content="0" * 64, calibration="c")\n'}[which]
    limit = rng.choice([1, 512, 2048])
    wrapped = ('import resource, sys\nfrom prsm_lube_ros.errors import InputError\n'
               f'resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))\ntry:\n'
               + ''.join(f'    {line}\n' for line in code.splitlines())
               + 'except InputError as exc:\n    print(exc, file=sys.stderr)\n    sys.exit(2)\n')
    result = subprocess.run([sys.executable, '-c', wrapped], capture_output=True, text=True, timeout=120)
    if 'Traceback' in result.stderr:
        return 'traceback', result.stderr[-300:]
    if result.returncode == 0:      # it fitted under the limit: then it must be whole
        return ('ok', '') if _whole(which, target) else ('damaged_output', f'{which} written but not whole')
    left = [p.name for p in out.rglob('*') if p.name.endswith('.tmp')]
    if (before is not None and target.read_bytes() != before) or left:
        return 'damaged_output', f'{which}: earlier file changed or temporaries {left}'
    return _refusal(result.stderr.strip(), str(target))


def _whole(which: str, target: Path) -> bool:
    """An output that was written is complete: it loads."""
    from prsm_lube_ros.errors import InputError
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    from prsm_lube_ros.fleet.history import read_table
    try:
        {'json': lambda: json.loads(target.read_text()), 'calibration': lambda: load_calibration(target),
         'history': lambda: read_table(target)}[which]()
        return True
    except (InputError, ValueError, OSError):
        return False


def wedged_service(work: Path, seeds: dict, rng: random.Random) -> tuple[str, str]:
    """The service's request path: a FIFO storage file, then a valid request, each within WEDGE_SECONDS."""
    from prsm_lube_ros.estimation.windowing import WindowSettings
    from prsm_lube_ros.nodes.calibration_request import calibrate_from_request
    root = work / 'recordings'
    root.mkdir()
    piped = _bag(root, seeds, 'piped')
    storage = next(piped.glob('*.mcap'))
    storage.unlink()
    os.mkfifo(storage)
    shutil.copytree(seeds['calibratable'], root / 'good')

    def request(name: str):
        return calibrate_from_request([name], 1.0, folder=root, lead=0.005, settings=WindowSettings(),
                                      namespace='/prsm', min_axial_load=1.0)
    outcome, detail = _refused(lambda: request('piped'), 'piped')
    if outcome != 'refused':
        return outcome, detail
    answer, detail = _refused(lambda: request('good'), 'good')
    if answer == 'wedged':
        return 'wedged', 'the next request was not answered'
    if answer == 'silent':          # answered with a fit: what the case must do
        return 'ok', ''
    return answer, f'the valid request: {detail}'


CASES = {name: globals()[name] for name in KINDS}
