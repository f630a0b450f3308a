#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The floor under ``prsm-lube assess`` with the condition indicators on: the bytes read once, then their transforms.

Usage: ``python benchmarks/indicator_floor.py BAG --rate HZ --windows N --band LOW HIGH --parts P [P ...]
[--window S]``.

:mod:`bytes_floor` reads the recording's bytes once; this does that and then
only the arithmetic the band RMS and the condition indicators
(:mod:`prsm_lube_ros.estimation.condition_indicators`) cannot do without, on
as many windows as ``assess`` gives indicators (``--windows``), in plain numpy
and with nothing of this package imported:

* one ``rfft`` of every window (the band RMS by Parseval; the indicators reuse it);
* one inverse transform of the band (kurtosis, crest factor and the Gaussian part);
* the fast kurtogram's 1/3-binary tree: at each level of ``--parts`` bands
  (those every window of the recording is served, its fastest window's
  narrowest) every band's bins zero-padded to a power of two and
  inverse-transformed, and the two moments of ``|z|^2`` its spectral kurtosis needs;
* one envelope spectrum per window (of the narrowest band, the cheapest).

No decoding, no windowing, no order tracking, no peak search, no assessment and
no JSON: as a whole process it is what an ``assess`` that keeps these indicators
cannot beat.  The windows' samples are the file's bytes (as float64), so the
transforms' inputs are as many as the hour's samples and their values do not
matter to the time.  Prints the number of windows and a checksum.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np


def main() -> None:
    """Read the bytes once, transform them as the band RMS and indicators do, print a checksum."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('bag', type=Path)
    parser.add_argument('--rate', type=float, required=True, help='sample rate of the vibration, Hz')
    parser.add_argument('--windows', type=int, required=True, help='windows the indicators are computed on')
    parser.add_argument('--band', type=float, nargs=2, required=True, metavar=('LOW', 'HIGH'),
                        help='analysis band, Hz')
    parser.add_argument('--parts', type=int, nargs='+', required=True,
                        help='band counts of the kurtogram levels every window is served')
    parser.add_argument('--window', type=float, default=1.0, help='window length, s (default 1)')
    parser.add_argument('--batch', type=int, default=1 << 18, help='samples transformed at once (default 2^18)')
    args = parser.parse_args()
    root = args.bag
    files = [p for p in sorted(root.rglob('*') if root.is_dir() else [root]) if p.is_file()]
    data = np.concatenate([np.fromfile(p, dtype=np.uint8) for p in files]) if len(files) > 1 \
        else np.fromfile(files[0], dtype=np.uint8)
    total = int(data.sum(dtype=np.uint64))          # every byte touched once, as bytes_floor does
    n = int(round(args.window * args.rate))
    windows = args.windows
    if data.size < windows * n:
        data = np.resize(data, windows * n)
    df = args.rate / n
    lo, hi = max(1, math.ceil(args.band[0] / df)), min(n // 2 - 1, math.floor(args.band[1] / df))
    width = hi - lo + 1
    chunk = max(1, args.batch // n)
    levels = [(parts, width // parts, 1 << int(math.ceil(math.log2(max(width // parts, 8))))) for parts in args.parts]
    # Buffers made once and reused (a fresh array of a few MB costs its page faults again each time).
    padded = np.empty(chunk * max(parts * size for parts, _, size in levels), dtype=complex)
    power = np.empty(padded.size)
    samples = np.empty((chunk, n))
    spectra = np.empty((chunk, n // 2 + 1), dtype=complex)
    in_band = np.zeros_like(spectra)
    signals = np.empty_like(samples)
    checksum = 0.0
    for start in range(0, windows, chunk):
        count = min(windows, start + chunk) - start
        rows = samples[:count]
        rows[...] = data[start * n:(start + count) * n].reshape(count, n)
        spec = np.fft.rfft(rows, axis=1, out=spectra[:count])
        band = spec[:, lo:hi + 1]
        band_power = np.einsum('ij,ij->i', band.real, band.real) + np.einsum('ij,ij->i', band.imag, band.imag)
        in_band[:count, lo:hi + 1] = band
        signal = np.fft.irfft(in_band[:count], n, axis=1, out=signals[:count])
        squares = np.square(signal, out=signal)
        checksum += float(band_power.sum() + np.square(squares, out=squares).mean())
        for parts, bins, size in levels:
            z = padded[:count * parts * size].reshape(count, parts, size)
            z[..., :bins] = spec[:, lo:lo + parts * bins].reshape(count, parts, bins)
            z[..., bins:] = 0.0
            np.fft.ifft(z, axis=2, out=z)
            envelope = np.abs(z[:, 0])       # the envelope spectrum below is taken of the narrowest level's
            interleaved = z.view(np.float64)     # |z|^2 as re^2 + im^2 over the interleaved floats
            np.square(interleaved, out=interleaved)
            p = np.add(interleaved[..., 0::2], interleaved[..., 1::2], out=power[:z.size].reshape(z.shape))
            mean = p.mean(axis=-1)
            checksum += float((np.square(p, out=p).mean(axis=-1) / mean ** 2).sum())
        checksum += float(np.abs(np.fft.rfft(envelope - envelope.mean(axis=1, keepdims=True), axis=1)).sum())
    print(windows, total, checksum)


if __name__ == '__main__':
    main()
