# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Open a local HTML page in headless Chromium (Debian's package) and read every image's natural width.

A probe page beside the page under test loads it in an iframe and writes,
once it has loaded, ``IMAGES <count>;<naturalWidth> <src>;...`` into its own
DOM, which ``chromium --dump-dom`` prints.  A figure that failed to load has
naturalWidth 0.  ``tools/install-browser`` installs chromium (``.ci/run`` calls it).
"""
import re
import shutil
import subprocess

PROBE = """<!DOCTYPE html><html><body><pre id="out">pending</pre><iframe id="page" src="{page}"></iframe><script>
document.getElementById('page').addEventListener('load', function () {{
  var found = [];
  try {{
    var images = this.contentDocument.images;
    for (var i = 0; i < images.length; i++) {{
      found.push((images[i].complete ? images[i].naturalWidth : -1) + ' ' + images[i].getAttribute('src'));
    }}
    document.getElementById('out').textContent = 'IMAGES ' + images.length + ';' + found.join(';');
  }} catch (error) {{
    document.getElementById('out').textContent = 'ERROR ' + error;
  }}
}});
</script></body></html>
"""
FLAGS = ('--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
         '--disable-component-update', '--disable-sync', '--no-first-run', '--allow-file-access-from-files',
         '--virtual-time-budget=10000', '--dump-dom')


def chromium() -> str | None:
    """Path of the chromium executable, None when it is not installed."""
    return shutil.which('chromium') or shutil.which('chromium-browser')


def image_widths(page, profile) -> dict:
    """{src: naturalWidth} of every <img> of ``page`` once loaded in headless Chromium (fresh ``profile`` dir)."""
    probe = page.parent / f'.probe_{page.stem}.html'
    probe.write_text(PROBE.format(page=page.name))
    try:
        result = subprocess.run([chromium(), *FLAGS, f'--user-data-dir={profile}', probe.as_uri()],
                                capture_output=True, text=True, timeout=120)
    finally:
        probe.unlink()
    match = re.search(r'<pre id="out">(.*?)</pre>', result.stdout, re.S)
    assert match, f'chromium printed no probe result (status {result.returncode}): {result.stderr[-2000:]}'
    text = match.group(1)
    assert text.startswith('IMAGES '), f'the probe could not read the page: {text}'
    count, *entries = text[len('IMAGES '):].split(';')
    widths = {}
    for entry in filter(None, entries):
        width, src = entry.split(' ', 1)
        widths[src] = int(width)
    assert len(widths) == int(count), text
    return widths
