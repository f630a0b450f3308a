# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``out/demo/index.html``: every step of ``prsm-lube demo`` on one page, figures, tables and checks.

Plain HTML with relative links (the folder can be moved or served as it is);
figures are the PNG files the steps wrote, so the page shows what the files hold.
"""
from __future__ import annotations

import datetime
import html
import os
from pathlib import Path

from ..atomic_file import write_text_atomically

__all__ = ['STYLE', 'write_page']

STYLE = """
body { font-family: sans-serif; max-width: 60em; margin: 2em auto; padding: 0 1em; color: #222; }
h2 { border-bottom: 1px solid #ccc; padding-bottom: .2em; }
.pass { color: #176b1d; font-weight: bold; } .fail { color: #a40e0e; font-weight: bold; }
table { border-collapse: collapse; margin: .5em 0 1em; font-size: 90%; }
td, th { border: 1px solid #ccc; padding: .2em .5em; text-align: left; }
pre { background: #f4f4f4; padding: .5em; overflow-x: auto; white-space: pre-wrap; font-size: 85%; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 85%; color: #555; }
"""


def _verdict(passed: bool) -> str:
    return '<span class="pass">PASS</span>' if passed else '<span class="fail">FAIL</span>'


def _relative(path: str | Path, folder: Path) -> str:
    return html.escape(Path(os.path.relpath(Path(path).resolve(), folder.resolve())).as_posix(), quote=True)


def _table(caption: str, header: list, rows: list) -> str:
    cells = ''.join(f'<th>{html.escape(str(h).strip())}</th>' for h in header)
    body = ''.join('<tr>' + ''.join(f'<td>{html.escape(str(c).strip())}</td>' for c in row) + '</tr>' for row in rows)
    if len(header) == 1:            # a command's output: keep its columns
        text = '\n'.join(str(row[0]) for row in rows)
        return f'<p>{html.escape(caption)}</p><pre>{html.escape(text)}</pre>'
    return f'<table><caption>{html.escape(caption)}</caption><tr>{cells}</tr>{body}</table>'


def write_page(folder: Path, steps: list, command: str) -> Path:
    """Write ``folder/index.html`` for ``steps`` (:class:`~.demo_steps.StepResult`); returns its path."""
    folder = Path(folder)
    passed = all(step.passed for step in steps)
    parts = [f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>prsm_lube_ros demo</title>'
             f'<style>{STYLE}</style></head><body>',
             '<h1>prsm_lube_ros: the demo</h1>',
             f'<p>Command: <code>{html.escape(command)}</code>, '
             f'{datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}. '
             f'Result: {_verdict(passed)} ({sum(s.passed for s in steps)}/{len(steps)} steps).</p><ul>']
    for step in steps:
        parts.append(f'<li><a href="#step{step.number}">Step {step.number}: {html.escape(step.title)}</a> '
                     f'{_verdict(step.passed)} ({step.seconds:.0f} s)</li>')
    parts.append('</ul>')
    for step in steps:
        parts.append(f'<h2 id="step{step.number}">Step {step.number}: {html.escape(step.title)} '
                     f'{_verdict(step.passed)}</h2><p>{html.escape(step.shows)}</p>')
        if step.lines:
            parts.append('<pre>' + html.escape('\n'.join(step.lines)) + '</pre>')
        parts.append('<ul>' + ''.join(f'<li>{html.escape(text)}: {_verdict(ok)}</li>' for text, ok in step.checks)
                     + '</ul>')
        for caption, header, rows in step.tables:
            parts.append(_table(caption, header, rows))
        for path, caption in step.figures:
            parts.append(f'<figure><img src="{_relative(path, folder)}" alt="{html.escape(caption, quote=True)}">'
                         f'<figcaption>{html.escape(caption)}</figcaption></figure>')
        if step.links:
            parts.append('<p>Files: ' + ', '.join(f'<a href="{_relative(path, folder)}">{html.escape(text)}</a>'
                                                  for path, text in step.links) + '</p>')
    parts.append('</body></html>\n')
    page = folder / 'index.html'
    write_text_atomically(page, '\n'.join(parts))
    return page
