#!/usr/bin/env python3
"""Writes scipy reference vectors for the aras-signal filter tests.

Run from this directory with numpy and scipy installed (any venv outside the
repository):  python make_reference.py  ->  butterworth.json

Floats are written with Python's repr, which round-trips f64 exactly.
"""
import json

import numpy as np
import scipy
from scipy import signal

# (order, cut-off Hz, sample rate Hz). Orders 1-8; cut-offs from 0.3% to 45%
# of the sample rate; (3, 25, 100) puts the real pole exactly at z = 0.
SOS_CASES = [
    (1, 5.0, 100.0),
    (2, 10.0, 1000.0),
    (3, 0.3, 10.0),
    (3, 25.0, 100.0),
    (4, 20.0, 1000.0),
    (5, 45.0, 100.0),
    (6, 2.5, 50.0),
    (7, 100.0, 1000.0),
    (8, 5.0, 200.0),
]
BA_CASES = [(1, 5.0, 100.0), (2, 10.0, 1000.0), (3, 0.3, 10.0), (4, 20.0, 1000.0)]


def test_signal(rng, n, fs):
    t = np.arange(n) / fs
    return (
        np.sin(2 * np.pi * 1.3 * t)
        + 0.4 * np.cos(2 * np.pi * 0.21 * fs * t + 0.3)
        + 0.2 * rng.standard_normal(n)
        + 0.5
        + 0.01 * np.arange(n)
    )


def main():
    rng = np.random.default_rng(20261101)
    out = {"scipy_version": scipy.__version__, "sos": [], "ba": []}
    for order, fc, fs in SOS_CASES:
        sos = signal.butter(order, fc, fs=fs, output="sos")
        ntaps = 2 * len(sos) + 1 - min((sos[:, 2] == 0).sum(), (sos[:, 5] == 0).sum())
        padlen = 3 * int(ntaps)
        signals = []
        # Shortest accepted length, an odd length, and a longer record.
        for n in (padlen + 1, 2 * padlen + 3, 257):
            x = test_signal(rng, n, fs)
            y = signal.sosfiltfilt(sos, x)
            signals.append({"x": x.tolist(), "y": y.tolist()})
        out["sos"].append(
            {
                "order": order,
                "cutoff_hz": fc,
                "sample_rate_hz": fs,
                "sos": sos.tolist(),
                "zi": signal.sosfilt_zi(sos).tolist(),
                "padlen": padlen,
                "signals": signals,
            }
        )
    for order, fc, fs in BA_CASES:
        b, a = signal.butter(order, fc, fs=fs)
        padlen = 3 * max(len(a), len(b))
        signals = []
        for n in (padlen + 1, 101):
            x = test_signal(rng, n, fs)
            y = signal.filtfilt(b, a, x)
            signals.append({"x": x.tolist(), "y": y.tolist()})
        out["ba"].append(
            {
                "order": order,
                "cutoff_hz": fc,
                "sample_rate_hz": fs,
                "b": b.tolist(),
                "a": a.tolist(),
                "padlen": padlen,
                "signals": signals,
            }
        )
    with open("butterworth.json", "w") as f:
        json.dump(out, f)
        f.write("\n")


if __name__ == "__main__":
    main()
