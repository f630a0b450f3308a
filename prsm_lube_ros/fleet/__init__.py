# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Many actuators over time: the Parquet history, parallel and Dask assessment, trend and forecast.

Owns: the history store (``history``: a Parquet dataset of runs and windows
partitioned by actuator and date, one file per recording, written atomically),
assessing many recordings serially, in processes or on a Dask cluster with the
same results (``parallel``), and the depletion fit and threshold-crossing
forecast per actuator (``forecast``).

:func:`prsm_lube_ros.fleet.forecast.forecast_summaries` (history folder,
actuator ids, warn and error levels) returns each actuator's forecast as short
key/value strings, ready for a diagnostics KeyValue list, from one read of the
history; :func:`~prsm_lube_ros.fleet.forecast.forecast_summary` does one.

May import: base, physics, recording, estimation.  pyarrow is imported by
``history`` only, dask.distributed by ``parallel`` only when a scheduler is
asked for, so ``prsm-lube assess`` without these options pays for neither.
"""
