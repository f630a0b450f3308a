# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Many actuators over time: the Parquet history, parallel and Dask assessment, trend and forecast.

Owns: the history store (``history``: one folder per recording holding its
runs and windows as Parquet, committed in one rename, consistent for plain
readers after any kill), assessing many recordings serially, in processes or
on a Dask cluster with the same results (``parallel``; connecting to Dask in
``scheduler``), the depletion fit and threshold-crossing forecast per actuator
(``forecast``; in words: ``forecast_summary``; none from a suspected surface defect on: ``defects``), what a
maintenance planner reads off it as of a date
(``planner``), scoring a forecast made from an earlier cut of the history
(``backtest``) and the service logs (``service_log``).

:func:`prsm_lube_ros.fleet.forecast_summary.forecast_summaries` (history folder,
actuator ids, warn and error levels) returns each actuator's forecast as short
key/value strings, ready for a diagnostics KeyValue list, from one read of the
history; :func:`~prsm_lube_ros.fleet.forecast_summary.forecast_summary` does one.

May import: base, physics, recording, estimation.  pyarrow is imported by
``history`` only, dask.distributed by ``parallel`` only when a scheduler is
asked for, so ``prsm-lube assess`` without these options pays for neither.
"""
