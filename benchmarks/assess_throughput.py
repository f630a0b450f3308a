#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Assessment throughput on a one-hour 4 kHz recording, beside the bare read, and peak memory.

The recordings are the rig simulator's endurance bags (the six conditions of
the paper cycled, rewinds included): 4 kHz acceleration in 0.1 s blocks,
joint states at 100 Hz, load at 50 Hz, temperature at 1 Hz, storage mcap.
Each measurement runs in a fresh subprocess so its peak resident memory
(``VmHWM``; ``ru_maxrss`` would carry over the parent's peak) is its own:

* ``bare read``: every message read, decompressed and split, nothing decoded
  (:func:`prsm_lube_ros.recording.reader.bare_read`);
* ``assess``: what ``prsm-lube assess`` does -- read, decode, window, assess
  every window and run with a calibration fitted beforehand.

Both are timed best of ``--repeat``.  A 15-minute and a one-hour recording are
assessed so flat memory shows as equal peaks; the hour is measured again with
zstd chunk compression, where the bare read includes decompression.

Then whole processes, as a user feels them (interpreter start-up and imports
included), median wall and CPU time of ``--repeat`` rounds, the commands of a
round run one after another so a loaded machine loads them alike:
``prsm-lube --help``; ``prsm-lube assess BAG --calibration C --json OUT`` on the
hour (band and condition indicators on: the calibration has a band and a
baseline), with this code and, given ``--before CHECKOUT``, with the code of
that checkout (a worktree of ``main``: the same file, machine and run); beside
them the obvious alternative, a short rosbags script that reads and
deserializes the same vibration messages and does less
(``benchmarks/rosbags_baseline.py``), and the floor, the file's bytes read once
with numpy (``benchmarks/bytes_floor.py``), and that floor with the transforms
the band RMS and the condition indicators cannot do without, in plain numpy
(``benchmarks/indicator_floor.py``: one FFT a window, the band's inverse, the
kurtogram's levels every window is served, an envelope spectrum).  The ratios
assess / rosbags script and assess / floor are printed beside them, and the
second floor's over the rosbags script: where it is above 0.5, no assess that
keeps these indicators can reach half the script's time.  Results go to
``benchmarks/results/<--name>.{json,md}`` (default ``assess_throughput``).

With ``--phases``, where the CPU of ``assess`` goes, with this code and the
``--before`` checkout's, each in a fresh process, best of ``--repeat``: the
imports of the command, reading and windowing the hour with the condition
indicators off, the indicators (the same with them on, less that), assessing
the windows and runs, and writing the JSON (compact, as ``--json`` does).

Usage: ``python benchmarks/assess_throughput.py [--repeat 3] [--data DIR] [--before CHECKOUT]
[--processes-only] [--phases] [--name NAME]``
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
from pathlib import Path
import subprocess
import sys
import time

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'


def child(kind: str, bag: str, calibration: str) -> None:
    """Run one measurement in this process and print a JSON line."""
    sys.path.insert(0, str(ROOT))
    from read_memory import peak_rss_mib   # beside this file
    from prsm_lube_ros.physics.actuator import Actuator
    from prsm_lube_ros.estimation.pipeline import assess_recording, recording_windows
    from prsm_lube_ros.recording.reader import bare_read
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    from prsm_lube_ros.recording.typestore import contract_typestore
    # One-time set-up of a process (the ROS type store the layout checks use): timed apart,
    # so the figures below are throughput on the recording itself.
    setup_start = time.perf_counter()
    contract_typestore()
    setup = time.perf_counter() - setup_start
    start = time.perf_counter()
    if kind == 'bare':
        messages = bare_read(bag)
        detail = {'messages': messages}
    else:
        calib = load_calibration(calibration)
        windows = recording_windows(bag, lead=Actuator().lead)
        result = assess_recording(windows, calib)
        detail = {'windows': len(result.windows), 'runs': len(result.runs),
                  'assessed_runs': sum(1 for r in result.runs if not r.reason)}
    elapsed = time.perf_counter() - start
    peak_mib = peak_rss_mib()
    print(json.dumps({'kind': kind, 'seconds': elapsed, 'setup_seconds': setup, 'peak_rss_mib': peak_mib,
                      **detail}))


def phases_child(bag: str, calibration: str) -> None:
    """CPU seconds of each phase of ``assess`` on ``bag`` in this process; print them as a JSON line."""
    start = time.process_time()
    from dataclasses import replace
    from prsm_lube_ros.cli import assess, common   # noqa: F401  (the command's imports)
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    from prsm_lube_ros.estimation.pipeline import assess_recording, assessment_json, recording_windows
    from prsm_lube_ros.estimation.windowing import WindowSettings
    from prsm_lube_ros.physics.actuator import Actuator
    lead = Actuator().lead
    marks = {'imports': time.process_time() - start}
    calib = load_calibration(calibration)
    settings = WindowSettings(band=calib.band)
    clock = time.process_time()
    recording_windows(bag, lead=lead, settings=replace(settings, condition_indicators=False))
    marks['reading and windowing'] = time.process_time() - clock
    clock = time.process_time()
    windows = recording_windows(bag, lead=lead, settings=settings)
    marks['condition indicators'] = time.process_time() - clock - marks['reading and windowing']
    clock = time.process_time()
    result = assess_recording(windows, calib)
    marks['assessing windows and runs'] = time.process_time() - clock
    clock = time.process_time()
    common.write_json(Path(bag).parent / 'phases.json', assessment_json([result], calib), indent=None)
    marks['writing the JSON'] = time.process_time() - clock
    print(json.dumps(marks))


def process_env(code: Path) -> dict[str, str]:
    """The environment of a measured process running ``code``: first on PYTHONPATH, its bytecode cached.

    An installed package runs from the bytecode pip compiled; a shell that sets
    ``PYTHONDONTWRITEBYTECODE`` would make every process compile this
    package's modules from source again (0.08 s of CPU a process), so it is
    dropped and one unmeasured round writes the cache first.
    """
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(code), os.environ.get('PYTHONPATH', '')]))
    env.pop('PYTHONDONTWRITEBYTECODE', None)
    return env


def phases(bag: Path, calibration: Path, repeat: int, checkouts: dict[str, Path]) -> dict[str, dict[str, float]]:
    """Per checkout (name -> code), the least CPU seconds of each phase over ``repeat`` fresh processes."""
    found: dict[str, dict[str, float]] = {}
    for _ in range(repeat):
        for name, code in checkouts.items():
            env = process_env(code)
            out = subprocess.run([sys.executable, __file__, '--phases-child', str(bag), str(calibration)],
                                 check=True, capture_output=True, text=True, cwd=code, env=env).stdout
            marks = json.loads(out.strip().splitlines()[-1])
            best = found.setdefault(name, marks)
            for phase, seconds in marks.items():
                best[phase] = min(best[phase], seconds)
    return found


def measure(kind: str, bag: Path, calibration: Path, repeat: int) -> dict:
    """Best of ``repeat`` fresh subprocesses."""
    from read_memory import best_of_children   # beside this file
    return best_of_children([sys.executable, __file__, '--child', kind, str(bag), str(calibration)], repeat)


def whole_processes(commands: dict[str, tuple[list[str], Path]], repeat: int) -> dict[str, dict]:
    """Median wall and CPU time (s) of each command run as a fresh process, ``repeat`` interleaved rounds.

    ``commands``: name -> (argv, checkout whose code it runs: cwd and PYTHONPATH).
    """
    import resource
    import statistics
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in commands}
    for argv, code in commands.values():      # the unmeasured round: bytecode written, files in the page cache
        subprocess.run(argv, check=True, capture_output=True, cwd=code, env=process_env(code))
    for _ in range(repeat):
        for name, (argv, code) in commands.items():
            env = process_env(code)
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            subprocess.run(argv, check=True, capture_output=True, cwd=code, env=env)
            wall = time.perf_counter() - start
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            times[name].append((wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime))
    return {name: {'wall_s': statistics.median(w for w, _ in runs), 'cpu_s': statistics.median(c for _, c in runs),
                   'wall_runs_s': [w for w, _ in runs]} for name, runs in times.items()}


def prepare(data: Path) -> tuple[dict, Path]:
    """Simulate (once) the recordings and a calibration; return {label: (bag, seconds)}, calibration."""
    sys.path.insert(0, str(ROOT))
    from prsm_lube_ros.physics.actuator import Actuator
    from prsm_lube_ros.estimation.pipeline import calibrate_recordings, recording_windows
    from prsm_lube_ros.estimation.calibration_file import save_calibration
    from prsm_lube_ros.simulation.recordings import simulate_experiment
    from read_memory import endurance_bag   # beside this file
    from prsm_lube_ros.simulation.rig_config import ExperimentPlan
    data.mkdir(parents=True, exist_ok=True)
    bags = {}
    for label, seconds, compression in (('15 min', 900.0, None), ('1 h', 3600.0, None),
                                        ('1 h, zstd chunks', 3600.0, 'zstd')):
        bags[label] = (endurance_bag(data, seconds, compression=compression), seconds)
    calibration = data / 'calibration.yaml'
    if not calibration.exists():
        reference = data / 'reference'
        if not reference.exists():
            simulate_experiment(reference, seed=2, plan=ExperimentPlan(stage_thetas=(1.0,)))
        windows = recording_windows(reference / 'stage_1', lead=Actuator().lead)
        save_calibration(calibrate_recordings([windows]), calibration)
    return bags, calibration


def main() -> int:
    """Measure, write the results, print the table."""
    if len(sys.argv) > 1 and sys.argv[1] == '--child':
        child(*sys.argv[2:5])
        return 0
    if len(sys.argv) > 1 and sys.argv[1] == '--phases-child':
        phases_child(*sys.argv[2:4])
        return 0
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--repeat', type=int, default=3)
    parser.add_argument('--data', type=Path, default=Path('/tmp/prsm_lube_bench'),
                        help='where the simulated recordings are cached (default /tmp/prsm_lube_bench)')
    parser.add_argument('--before', type=Path, default=None, metavar='CHECKOUT',
                        help='also time prsm-lube assess with the code of this checkout (e.g. a worktree of main)')
    parser.add_argument('--processes-only', action='store_true',
                        help='only the whole processes (leave out the in-process throughput and memory table)')
    parser.add_argument('--phases', action='store_true',
                        help='also where the CPU of assess goes (imports, windowing, indicators, assessing, JSON)')
    parser.add_argument('--name', default='assess_throughput', help='results file name (default assess_throughput)')
    args = parser.parse_args()
    bags, calibration = prepare(args.data)
    rows = [] if args.processes_only else throughput_rows(bags, calibration, args.repeat)
    hour_bag = bags['1 h'][0]
    processes = whole_processes(process_commands(hour_bag, calibration, args.data, args.before), args.repeat)
    ratios = process_ratios(processes)
    phase_cpu = {}
    if args.phases:
        checkouts = {'this code': ROOT} | ({'before': args.before.resolve()} if args.before else {})
        phase_cpu = phases(hour_bag, calibration, args.repeat, checkouts)
    goals = {'prsm-lube --help < 0.2 s': processes['prsm-lube --help']['wall_s'] < 0.2,
             'assess CPU <= 0.5 x the rosbags script\'s': ratios['assess (1 h)']['cpu_over_rosbags'] <= 0.5,
             'assess <= 0.5 x the rosbags script': ratios['assess (1 h)']['over_rosbags'] <= 0.5,
             'assess <= 3 x the floor': ratios['assess (1 h)']['over_floor'] <= 3.0,
             'the transforms\' floor <= 0.5 x the rosbags script (else the first goal is out of reach with these '
             'indicators)': ratios[INDICATOR_FLOOR]['over_rosbags'] <= 0.5}
    hour = next((r for r in rows if r['recording'] == '1 h'), None)
    if hour is not None:
        goals.update({'assess_x_realtime >= 5000': hour['assess_x_realtime'] >= 5000,
                      'assess_over_bare <= 2': hour['assess_over_bare'] <= 2.0})
    document = {'benchmark': 'assess_throughput', 'command': 'python benchmarks/assess_throughput.py '
                + ' '.join(sys.argv[1:]),
                'machine': {'python': platform.python_version(), 'processor': platform.processor() or
                            platform.machine(), 'cpus': _cpus(), 'load_average_1min_at_end': os.getloadavg()[0]},
                'repeat': args.repeat, 'rows': rows, 'whole_process': processes, 'ratios': ratios,
                'before': str(args.before) if args.before else None, 'phases_cpu_s': phase_cpu, 'goals': goals}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f'{args.name}.json').write_text(json.dumps(document, indent=1))
    lines = [f'# Assessment throughput (`{document["command"]}`)', '',
             f'Python {document["machine"]["python"]}, {document["machine"]["cpus"]} CPUs, 1-min load average '
             f'{document["machine"]["load_average_1min_at_end"]:.1f} at the end.', '']
    if rows:
        lines += [f'In-process, best of {args.repeat}; times exclude the one-time set-up of a process (building the '
                  'ROS type store for the layout checks), shown apart.', '',
                  '| recording | size MiB | bare read s | assess s | assess x real time | assess / bare '
                  '| peak RSS bare MiB | peak RSS assess MiB | one-time set-up s |',
                  '|---|---|---|---|---|---|---|---|---|']
        for r in rows:
            lines.append(f'| {r["recording"]} | {r["size_mib"]:.0f} | {r["bare_read_s"]:.3f} | {r["assess_s"]:.3f} | '
                         f'{r["assess_x_realtime"]:.0f} | {r["assess_over_bare"]:.2f} | {r["bare_peak_rss_mib"]:.0f} | '
                         f'{r["assess_peak_rss_mib"]:.0f} | {r["setup_s"]:.3f} |')
        lines.append('')
    lines += [f'Whole processes on the hour ({hour_bag.name}), start to exit, median of {args.repeat} interleaved '
              'rounds after an unmeasured one, bytecode cached as an installed package has it'
              + (f'; "before": the code of {args.before}' if args.before else '') + ':', '',
              '| command | wall s | CPU s | wall / rosbags script | wall / floor | CPU / rosbags script '
              '| CPU / floor |',
              '|---|---|---|---|---|---|---|']
    for name, measured in processes.items():
        ratio = ratios.get(name, {})
        lines.append(f'| {name} | {measured["wall_s"]:.3f} | {measured["cpu_s"]:.3f} | '
                     f'{_ratio(ratio.get("over_rosbags"))} | {_ratio(ratio.get("over_floor"))} | '
                     f'{_ratio(ratio.get("cpu_over_rosbags"))} | {_ratio(ratio.get("cpu_over_floor"))} |')
    if phase_cpu:
        names = list(phase_cpu)
        lines += ['', f'Where the CPU of assess goes on the hour, in-process, s, least of {args.repeat} fresh processes'
                  ' (the indicators: windowing with them less windowing without):', '',
                  '| phase | ' + ' | '.join(names) + ' |', '|---|' + '---|' * len(names)]
        for phase in phase_cpu[names[0]]:
            cells = [f'{phase_cpu[name].get(phase, float("nan")):.3f}' for name in names]
            lines.append(f'| {phase} | ' + ' | '.join(cells) + ' |')
        lines.append('| sum | ' + ' | '.join(f'{sum(phase_cpu[name].values()):.3f}' for name in names) + ' |')
    lines += ['', 'Goals: ' + ', '.join(f'{goal}: {"met" if ok else "NOT met"}' for goal, ok in goals.items())]
    (RESULTS / f'{args.name}.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


def throughput_rows(bags: dict, calibration: Path, repeat: int) -> list[dict]:
    """In-process bare read and assessment of each recording, best of ``repeat`` fresh processes."""
    rows = []
    for label, (bag, seconds) in bags.items():
        size = sum(p.stat().st_size for p in bag.rglob('*') if p.is_file())
        bare = measure('bare', bag, calibration, repeat)
        assess = measure('assess', bag, calibration, repeat)
        rows.append({'recording': label, 'duration_s': seconds, 'size_mib': size / 2 ** 20,
                     'bare_read_s': bare['seconds'], 'assess_s': assess['seconds'],
                     'assess_x_realtime': seconds / assess['seconds'],
                     'bare_x_realtime': seconds / bare['seconds'],
                     'assess_over_bare': assess['seconds'] / bare['seconds'],
                     'bare_peak_rss_mib': bare['peak_rss_mib'], 'assess_peak_rss_mib': assess['peak_rss_mib'],
                     'setup_s': assess['setup_seconds'],
                     'messages': bare['messages'], 'windows': assess['windows'],
                     'assessed_runs': assess['assessed_runs']})
    return rows


def process_commands(hour_bag: Path, calibration: Path, data: Path,
                     before: Path | None) -> dict[str, tuple[list[str], Path]]:
    """The whole-process commands: name -> (argv, checkout whose code runs)."""
    cli = [sys.executable, '-m', 'prsm_lube_ros.cli']
    assess = ['assess', str(hour_bag), '--calibration', str(calibration)]
    commands = {'prsm-lube --help': (cli + ['--help'], ROOT),
                'assess (1 h)': (cli + assess + ['--json', str(data / 'assess.json')], ROOT)}
    if before is not None:
        commands['assess (1 h), before'] = (cli + assess + ['--json', str(data / 'assess_before.json')],
                                            before.resolve())
    commands['rosbags script (1 h)'] = ([sys.executable, str(ROOT / 'benchmarks' / 'rosbags_baseline.py'),
                                         str(hour_bag)], ROOT)
    commands['floor: bytes read once (1 h)'] = ([sys.executable, str(ROOT / 'benchmarks' / 'bytes_floor.py'),
                                                 str(hour_bag)], ROOT)
    commands[INDICATOR_FLOOR] = ([sys.executable, str(ROOT / 'benchmarks' / 'indicator_floor.py'), str(hour_bag)]
                                 + indicator_floor_arguments(hour_bag, data / 'assess.json', calibration), ROOT)
    return commands


#: The row of the floor with the indicators' transforms (``benchmarks/indicator_floor.py``).
INDICATOR_FLOOR = 'floor + the transforms of band and indicators (1 h)'


def indicator_floor_arguments(hour_bag: Path, assessment: Path, calibration: Path) -> list[str]:
    """``indicator_floor.py``'s arguments for the hour: its windows with indicators, band, rate and tree levels.

    Read from ``assessment``, an ``assess --json`` of ``hour_bag`` (made here
    if there is none yet) and the calibration's band:
    the windows that have indicators, and the kurtogram levels every one of them
    is served (a band must carry :data:`ENVELOPE_HARMONICS` times the highest
    defect order at the window's speed), so the floor does no more than assess.
    """
    sys.path.insert(0, str(ROOT))
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    from prsm_lube_ros.estimation.condition_indicators import ENVELOPE_HARMONICS, TREE_PARTS
    from prsm_lube_ros.estimation.windowing import DEFAULT_DEFECT_ORDERS
    if not assessment.exists():
        subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'assess', str(hour_bag),
                        '--calibration', str(calibration), '--json', str(assessment)], check=True,
                       capture_output=True, cwd=ROOT, env=process_env(ROOT))
    windows = [w for w in json.loads(assessment.read_text())['windows']
               if w['condition_indicators'].get('kurtosis') is not None]
    rate = windows[0]['sample_rate']
    band = load_calibration(calibration).band
    n = int(round(rate))      # one-second windows
    lo, hi = max(1, math.ceil(band.low * n / rate)), min(n // 2 - 1, math.floor(band.high * n / rate))
    fastest = max(abs(w['screw_speed']) for w in windows) / (2.0 * math.pi)
    need = max(8, math.ceil(ENVELOPE_HARMONICS * max(o.order for o in DEFAULT_DEFECT_ORDERS) * fastest * n / rate))
    parts = [p for p in TREE_PARTS if (hi - lo + 1) // p >= need]
    return ['--rate', f'{rate:g}', '--windows', str(len(windows)), '--band', f'{band.low:g}', f'{band.high:g}',
            '--parts', *map(str, parts)]


def process_ratios(processes: dict[str, dict]) -> dict[str, dict]:
    """Each assess's wall time over the rosbags script's and over the floor's; the same for CPU time."""
    rosbags, floor = processes['rosbags script (1 h)'], processes['floor: bytes read once (1 h)']
    return {name: {'over_rosbags': measured['wall_s'] / rosbags['wall_s'],
                   'over_floor': measured['wall_s'] / floor['wall_s'],
                   'cpu_over_rosbags': measured['cpu_s'] / rosbags['cpu_s'],
                   'cpu_over_floor': measured['cpu_s'] / floor['cpu_s']}
            for name, measured in processes.items() if name.startswith('assess') or name == INDICATOR_FLOOR}


def _ratio(value: float | None) -> str:
    return '' if value is None else f'{value:.2f}'


def _cpus() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else os.cpu_count()


if __name__ == '__main__':
    sys.exit(main())
