"""The BorealTC layout: ``GROUND/imu_NN.csv`` (IMU, ~100 Hz) + ``GROUND/pro_NN.csv`` (drive, ~6.5 Hz)."""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from terrawatt_base.checks import check_text, fmt_number
from terrawatt_base.errors import DataError, FileFormatError, InvalidParameterError, UnknownNameError

from ..logs import InteractionLog, LogMeta
from .cleaning import (
    MAX_OMEGA_RADPS,
    MAX_SPEED_MPS,
    LogCleaning,
    bracket_accel,
    check_accel,
    check_current,
    check_limit,
    check_timing,
    check_track_width,
    clean_stream,
)
from .csv_table import read_csv_text, read_table

__all__ = ["BOREALTC_TRACK_WIDTH_M", "read_borealtc_run", "read_borealtc"]

_LOG = logging.getLogger(__name__)

#: Nominal (geometric) track width of the Clearpath Husky A200 used by the BorealTC reader.
#: A skid-steer robot's effective track width is larger and ground-dependent; pass a
#: fitted value as ``track_width_m`` when you have one.
BOREALTC_TRACK_WIDTH_M = 0.555
_BOREALTC_FILE = re.compile(r"^(imu|pro)_(\d+)\.csv$")


def read_borealtc_run(
    imu_csv: str | os.PathLike[str],
    pro_csv: str | os.PathLike[str],
    track_width_m: float = BOREALTC_TRACK_WIDTH_M,
    ground_label: str | None = None,
    *,
    robot: str = "husky_a200",
    cleaning: LogCleaning | None = None,
) -> InteractionLog:
    """Read one BorealTC run (``imu_NN.csv`` + ``pro_NN.csv``) into an InteractionLog.

    ``pro_NN.csv`` (``time,curL,curR,velL,velR``, ~6.5 Hz) gives the drive stream:
    measured wheel speeds (m/s) turned into ``v = (velL + velR) / 2`` and
    ``omega = (velR - velL) / track_width_m`` (``meta.velocity_source = "measured"``) and the
    motor currents (A). ``imu_NN.csv`` (``time,wx,wy,wz,ax,ay,az``, ~100 Hz) gives
    ``accel_z_mps2 = az`` (gravity included) and, when the file has the column,
    ``gyro_z_radps = wz`` (rad/s). Both clocks start at zero but the files end
    at different times; they are aligned on the overlap ``[max(starts), min(ends)]``: drive
    samples outside it are dropped, and the IMU keeps the samples from the last one at or
    before the first kept drive time to the first one at or after the last kept drive
    time, so every drive time lies inside the acceleration record. The counts dropped are
    written to ``meta.notes``.

    Parameters
    ----------
    imu_csv, pro_csv : path-like
        The two files of one run.
    track_width_m : float
        Track width B used for omega (m). The default is the Husky's geometric 0.555 m; a
        skid-steer robot's effective track width is larger (fit it when you can).
    ground_label : str, optional
        Run-level ground label (``read_borealtc`` passes the folder name, lowercased).
    robot : str
        Robot name for the metadata.
    cleaning : LogCleaning, optional
        Repairs, gaps and unit checks (:class:`~energy.io.cleaning.LogCleaning`, default none
        repaired, no gaps, units checked; see :mod:`energy.io`).

    Returns
    -------
    InteractionLog

    Raises
    ------
    FileFormatError
        A file is missing or unparsable.
    DataError
        Missing columns, empty files, unsorted/duplicated timestamps, NaNs or gaps (unless
        repaired/allowed), streams that do not overlap.
    UnitError
        Currents or speeds whose magnitude contradicts A or m/s; a stream rate outside
        [0.5 Hz, 10 kHz] or a run longer than a day (times in ms read as s); all with
        ``check_units``.
    InvalidParameterError, UnknownNameError
        Bad ``track_width_m``, ``ground_label`` or ``cleaning``.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        log = read_borealtc_run("SNOW/imu_00.csv", "SNOW/pro_00.csv", ground_label="snow")
    """
    track_width_m = check_track_width(track_width_m)
    if ground_label is not None:
        check_text("ground_label", ground_label)
    cleaning = LogCleaning.check(cleaning)
    repairs, allow_gaps, gap_factor = cleaning.repairs, cleaning.allow_gaps, cleaning.gap_factor
    imu_path, pro_path = Path(imu_csv), Path(pro_csv)
    pro = read_table(read_csv_text(pro_path), ("time", "curL", "curR", "velL", "velR"))
    imu = read_table(read_csv_text(imu_path), ("time", "az"), optional=("wz",))
    imu_cols = {k: imu[k] for k in ("az", "wz") if k in imu}
    src_p, src_i = str(pro_path), str(imu_path)
    tp, pc, _ = clean_stream(
        src_p, "drive stream", pro["time"], {k: pro[k] for k in ("curL", "curR", "velL", "velR")},
        repairs, allow_gaps, gap_factor,
    )
    ti, ic, _ = clean_stream(src_i, "IMU stream", imu["time"], imu_cols, repairs, allow_gaps, gap_factor)
    if cleaning.check_units:
        check_current(src_p, "curL", pc["curL"], "A")
        check_current(src_p, "curR", pc["curR"], "A")
        for k in ("velL", "velR"):
            check_limit(src_p, k, pc[k], MAX_SPEED_MPS, "m/s", "wheel speeds look like mm/s or cm/s")
        check_accel(src_i, "az", ic["az"])
        if "wz" in ic:
            check_limit(src_i, "wz", ic["wz"], MAX_OMEGA_RADPS, "rad/s", "gyro rates look like deg/s")
        check_timing(src_p, "drive stream", tp)
        check_timing(src_i, "IMU stream", ti)
    t0, t1 = max(tp[0], ti[0]), min(tp[-1], ti[-1])
    keep = (tp >= t0) & (tp <= t1)
    if t1 < t0 or not keep.any():
        raise DataError(
            f"{src_p} spans [{fmt_number(float(tp[0]), 9)}, {fmt_number(float(tp[-1]), 9)}] s and {src_i} spans [{fmt_number(float(ti[0]), 9)}, {fmt_number(float(ti[-1]), 9)}] s: "
            f"they do not overlap"
        )
    td = tp[keep]
    acc = bracket_accel(td, ti)
    dropped_d = int((~keep).sum())
    dropped_a = ti.size - (acc.stop - acc.start)
    vl, vr = pc["velL"][keep], pc["velR"][keep]
    notes = (
        f"BorealTC run; imu={src_i}; aligned on the overlap [{t0:g}, {t1:g}] s: dropped {dropped_d} drive "
        f"sample(s) outside it and {dropped_a} IMU sample(s) outside the kept drive span "
        f"[{td[0]:g}, {td[-1]:g}] s (bracketing samples kept); v=(velL+velR)/2, omega=(velR-velL)/{track_width_m:g} m"
    )
    if dropped_d or dropped_a:
        _LOG.debug("%s: %s", src_p, notes)
    return InteractionLog(
        time_s=td,
        v_mps=0.5 * (vl + vr),
        omega_radps=(vr - vl) / track_width_m,
        current_left_a=pc["curL"][keep],
        current_right_a=pc["curR"][keep],
        accel_time_s=ti[acc],
        accel_z_mps2=ic["az"][acc],
        gyro_z_radps=ic["wz"][acc] if "wz" in ic else None,
        meta=LogMeta(
            robot=robot,
            source=src_p,
            ground_label=ground_label,
            velocity_source="measured",
            track_width_m=track_width_m,
            notes=notes,
        ),
    )


def read_borealtc(
    directory: str | os.PathLike[str],
    grounds: Iterable[str] | None = None,
    **kwargs: Any,
) -> list[InteractionLog]:
    """Read every run of a BorealTC-layout directory (``GROUND/imu_NN.csv`` + ``GROUND/pro_NN.csv``).

    Parameters
    ----------
    directory : path-like
        Directory holding one sub-directory per ground (e.g. ``ASPHALT``, ``SNOW``).
    grounds : iterable of str, optional
        Ground folders to read (case-insensitive); all folders with run files by default.
    **kwargs
        Passed to :func:`read_borealtc_run` (``track_width_m``, ``robot``, ``cleaning``).

    Returns
    -------
    list of InteractionLog
        Sorted by ground folder name, then run number; ``meta.ground_label`` is the folder
        name lowercased.

    Raises
    ------
    FileFormatError
        ``directory`` does not exist or is not a directory.
    UnknownNameError
        A requested ground has no folder.
    DataError
        No runs found, or an ``imu_NN.csv`` without its ``pro_NN.csv`` (or the reverse);
        plus everything :func:`read_borealtc_run` raises.
    """
    root = Path(directory)
    if not root.is_dir():
        raise FileFormatError(f"BorealTC directory {str(root)!r} does not exist or is not a directory")
    if "ground_label" in kwargs:
        raise InvalidParameterError("read_borealtc takes ground labels from the folder names; do not pass ground_label")
    folders = {
        p.name: p for p in sorted(root.iterdir())
        if p.is_dir() and any(_BOREALTC_FILE.match(f.name) for f in p.iterdir())
    }
    if grounds is None:
        chosen = sorted(folders)
    else:
        try:
            wanted = [grounds] if isinstance(grounds, str) else list(grounds)
        except TypeError:
            raise InvalidParameterError(
                f"grounds must be a folder name or an iterable of folder names, got {grounds!r:.80}"
            ) from None
        by_lower = {name.lower(): name for name in folders}
        unknown = [g for g in wanted if not isinstance(g, str) or g.lower() not in by_lower]
        if unknown:
            raise UnknownNameError(
                f"grounds {unknown!r} have no folder in {str(root)!r}; available: {sorted(folders)!r}"
            )
        chosen = sorted({by_lower[g.lower()] for g in wanted})
    logs: list[InteractionLog] = []
    for name in chosen:
        runs: dict[int, dict[str, Path]] = {}
        for f in folders[name].iterdir():
            m = _BOREALTC_FILE.match(f.name)
            if m:
                runs.setdefault(int(m.group(2)), {})[m.group(1)] = f
        unpaired = sorted(str(p) for pair in runs.values() if len(pair) != 2 for p in pair.values())
        if unpaired:
            raise DataError(f"BorealTC files without their imu/pro partner: {unpaired!r}")
        for nn in sorted(runs):
            logs.append(read_borealtc_run(runs[nn]["imu"], runs[nn]["pro"], ground_label=name.lower(), **kwargs))
    if not logs:
        raise DataError(f"no BorealTC runs (GROUND/imu_NN.csv + pro_NN.csv) found in {str(root)!r}")
    return logs
