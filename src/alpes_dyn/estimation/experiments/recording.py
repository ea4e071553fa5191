"""Recordings of an experiment on the hand: the CSV format
that :func:`~alpes_dyn.estimation.identification.identification.identify` reads.

One row per sample, uniformly spaced, a header line naming the columns (any order):

=========================== ======== ==========================================================================
column                      unit     meaning
=========================== ======== ==========================================================================
``t``                       s        sample time, strictly increasing, uniform spacing (the sample period)
``run``                     --       optional: the run each sample belongs to, an integer, non-decreasing
``encoder_<motor>``         counts   motor encoder, q_m = (2 pi / counts_per_rev) counts (Section 3, eq. 3.13)
``torque_<motor>``          N m      measured motor torque, held until the next sample; or instead
``current_<motor>``         A        motor current, converted with a torque constant (``torque_constant``, N m/A)
``force_z``                 N        optional: fingertip normal force (FlexiForce, eq. 2.13)
``q_<joint>``               rad      optional: a joint angle measured now and then (camera, jig); empty elsewhere
``gravity_x,_y,_z``         m/s^2    optional, all three: gravity in the hand's base frame (its orientation)
``true_q_<joint>``          rad      optional: the true joint angles of a simulated experiment; never read by a fit
``held_out``                --       optional: 1 on the samples held out of the fit (each run's last ones: the
                                     experiment's stiction ramp, :mod:`~alpes_dyn.estimation.experiments.held_out`),
                                     0 elsewhere
=========================== ======== ==========================================================================

``<motor>`` and ``<joint>`` are the model's names (:attr:`Transmission.motor_names
<alpes_dyn.Transmission.motor_names>`, :attr:`Model.joint_names <alpes_dyn.Model.joint_names>`): on
``finger3`` the columns are ``t, encoder_finger, torque_finger`` and ``q_j1, q_j2, q_j3``. Only
``q_*`` and ``force_z`` may have empty cells; the true angles ``true_q_*`` are every joint's at every sample, or
not in the file (the RMSE of ``estimate --data`` needs them all). On the command line, ``identify`` and
``estimate --data`` read ``current_<motor>`` columns with ``--torque-constant NM_PER_A``. An encoder
reading far outside what the joints' ranges allow (more than the range and a motor turn beyond it) is
refused by name: it is not this model's encoder in counts; so is an encoder column of fractional values swinging no
more than the joints' range in degrees of the motor (the angle in radians or degrees), a torque beyond
:data:`~alpes_dyn.estimation.experiments.units.TORQUE_SCALE_LIMIT` times the file's ``tau_max`` (a current in A or mA) and a sample period over 0.1 s
(t in ms). Every defect is one
:class:`~alpes_dyn.errors.RecordingError` naming the column (and the row): an unknown or missing
column, a non-number (``1_0`` too: no digit separators), NaN where not allowed, time not increasing or not
uniform, a joint angle or gravity in the wrong unit (degrees, g: the gravity's norm must be 9.81 m/s^2 within
10 %), a recording too short or without excitation.

Several runs in one file (issue 39): a ``run`` column numbers the excitation runs of a bench session (any
integers, non-decreasing: 0 0 ... 0 1 1 ... 1). Each run is a recording of its own as above (at least
:data:`MIN_SAMPLES` samples, its time strictly increasing and uniform, every run at the same sample period);
between two runs the time may jump or start again, and the states jump: a fit starts each run from its own
initial state (:func:`~alpes_dyn.estimation.identification.identification.identify`), the parameters shared.
Without the column the file is one run, and a jump in its time is refused as before.
"""

from __future__ import annotations

import csv
import dataclasses
import itertools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...errors import RecordingError
from ...fileio import atomic_path, read_bytes
from ...limits import MAX_CSV_CELL, MAX_CSV_ROWS, MAX_RECORDING_BYTES, check_not_subnormal, check_physical
from ...model.robot import Model
from .csv_numbers import lines, plain_rows, refuse_empty_row
from .held_out import check_held_out, held_out_column
from .segments import MAX_SEGMENTS, excitation_parts, segment_starts  # noqa: F401  (exported from here, as before)
from .units import _check_encoder_columns, check_units

__all__ = ["Recording", "read_recording", "write_recording", "join_runs", "MIN_SAMPLES", "MAX_SEGMENTS",
           "segment_starts", "excitation_parts"]

MIN_SAMPLES = 100  # a shorter recording cannot tell a finger's dynamics

GRAVITY = 9.81
"""The gravity a recording's ``gravity_*`` columns (and an experiment's orientations) hold, m/s^2."""

GRAVITY_TOLERANCE = 0.1
"""Relative tolerance on the norm of a recorded gravity vector: 9.81 m/s^2 +- 10 % (an accelerometer's scale
error; a norm of 14.9 or of 1 m/s^2 is not the Earth's gravity in m/s^2, and a fit would read it as such)."""


def gravity_norm_off(gravity: np.ndarray) -> np.ndarray:
    """Indices of the rows of ``gravity`` (N, 3), m/s^2, whose norm is not :data:`GRAVITY` within
    :data:`GRAVITY_TOLERANCE`."""
    g = np.linalg.norm(np.atleast_2d(np.asarray(gravity, dtype=float)), axis=1)
    return np.flatnonzero(~(np.abs(g - GRAVITY) <= GRAVITY_TOLERANCE * GRAVITY))


@dataclass
class Recording:
    """A recorded (or simulated) experiment; every array has one row per sample.

    Attributes
    ----------
    t: (N,) s. encoder: (N, m) counts. torque: (N, m) N m (torque[k] held on [t_k, t_k+1)).
    motor_names (m,), joint_names (n,): the model's names.
    q: (N, n) rad, NaN where not measured, or None. force_z: (N,) N or None.
    gravity: (N, 3) m/s^2 or None. true_q: (N, n) rad or None (simulated experiments only).
    run: (N,) integers, non-decreasing: the run of each sample, or None (one run).
    held_out: (N,) bool: the samples held out of the fit (:mod:`~alpes_dyn.estimation.experiments.held_out`), or None.
    """

    t: np.ndarray
    encoder: np.ndarray
    torque: np.ndarray
    motor_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    q: np.ndarray | None = None
    force_z: np.ndarray | None = None
    gravity: np.ndarray | None = None
    true_q: np.ndarray | None = None
    run: np.ndarray | None = None
    held_out: np.ndarray | None = None

    @property
    def n_samples(self) -> int:
        return int(self.t.shape[0])

    def take(self, rows: slice | np.ndarray) -> "Recording":
        """The recording of some of this one's samples: every per-sample column taken, the names kept; not checked
        again.

        Parameters
        ----------
        rows : slice or numpy.ndarray
            The samples kept: a slice, an index array or a boolean mask (N,).

        Returns
        -------
        Recording
        """
        cut = {f.name: getattr(self, f.name)[rows] for f in dataclasses.fields(self)
               if isinstance(getattr(self, f.name), np.ndarray) and getattr(self, f.name).shape[:1] == (self.n_samples,)}
        return dataclasses.replace(self, **cut)

    def run_starts(self) -> np.ndarray:
        """(R + 1,) the first sample of each of the R runs, then the number of samples (one run without
        :attr:`run`)."""
        if self.run is None:
            return np.array([0, self.n_samples])
        cut = np.flatnonzero(np.diff(np.asarray(self.run)) != 0) + 1
        return np.concatenate([[0], cut, [self.n_samples]])

    @property
    def n_runs(self) -> int:
        return len(self.run_starts()) - 1

    @property
    def dt(self) -> float:
        """Sample period, s (within the runs: the time between runs is not a period)."""
        b = self.run_starts()
        t = np.asarray(self.t, dtype=float)
        return float(np.sum(t[b[1:] - 1] - t[b[:-1]]) / (self.n_samples - self.n_runs))

    @property
    def duration(self) -> float:
        """The time recorded, s: the runs' durations summed (one run: t[-1] - t[0])."""
        b = self.run_starts()
        t = np.asarray(self.t, dtype=float)
        return float(np.sum(t[b[1:] - 1] - t[b[:-1]]))

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV columns, in the documented order."""
        out = {"t": self.t}
        if self.run is not None:
            out["run"] = self.run
        for j, mname in enumerate(self.motor_names):
            out[f"encoder_{mname}"] = self.encoder[:, j]
            out[f"torque_{mname}"] = self.torque[:, j]
        if self.force_z is not None:
            out["force_z"] = self.force_z
        if self.q is not None:
            out.update({f"q_{jn}": self.q[:, i] for i, jn in enumerate(self.joint_names)})
        if self.gravity is not None:
            out.update({f"gravity_{a}": self.gravity[:, i] for i, a in enumerate("xyz")})
        if self.true_q is not None:
            out.update({f"true_q_{jn}": self.true_q[:, i] for i, jn in enumerate(self.joint_names)})
        if self.held_out is not None:
            out["held_out"] = self.held_out
        return out


WRITE_ROWS = 1 << 15
"""Rows :func:`write_recording` formats at a time."""


def write_recording(rec: Recording, path: str | Path) -> Path:
    """Write a recording as CSV in the documented column order (atomically: nothing is left at ``path`` if writing
    fails).

    Parameters
    ----------
    rec : Recording
        The recording (checked first, :func:`check_recording`).
    path : str or pathlib.Path
        The CSV file written (replaced if it exists).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    RecordingError
        A recording :func:`check_recording` refuses, or a file that cannot be written.
    """
    check_recording(rec)
    cols = {c: np.asarray(v, dtype=float) for c, v in rec.columns().items()}
    # atomic_path flushes the file to disk before it renames it over path
    with atomic_path(path, "recording", RecordingError) as tmp, open(tmp, "w", encoding="utf-8", newline="") as f:
        f.write(",".join(cols) + "\n")
        # WRITE_ROWS rows at a time, column by column (the cells formatted by map in C, not a Python loop over
        # the rows: 600 s of the hand is 18 million cells; a chunk's cells, not the record's, held at once),
        # each cell the repr of its float, "" for NaN, the run an integer
        for k0 in range(0, rec.n_samples, WRITE_ROWS):  # a loop over chunks of rows
            text = [_column_text(c, v[k0: k0 + WRITE_ROWS]) for c, v in cols.items()]
            f.write("\n".join(map(",".join, zip(*text))) + "\n")
    return Path(path)


def _column_text(name: str, values: np.ndarray) -> list[str]:
    """The cells of one column (N,) as :func:`write_recording` writes them: ``repr`` of the float, "" for NaN; the
    ``run`` column's as integers."""
    if name in ("run", "held_out"):
        return list(map(str, values.astype(np.int64).tolist()))
    cells = np.array(list(map(repr, values.tolist())), dtype=object)
    cells[np.isnan(values)] = ""
    return cells.tolist()


def _next_row(rows, p: Path) -> list[str] | None:
    """The next row of the CSV reader ``rows`` (None at the end); a one-line RecordingError for what csv refuses."""
    try:
        return next(rows)
    except StopIteration:
        return None
    except csv.Error as exc:  # a cell over the csv module's own limit (131072 characters)
        if "field larger" in str(exc):
            raise RecordingError(f"recording {str(p)!r}: a cell over the limit of {MAX_CSV_CELL} characters") from None
        raise RecordingError(f"recording {str(p)!r}: not a CSV file ({exc})") from None


def _finite(x: object) -> bool:
    """Whether the real number ``x`` is finite (an integer too large for a float is not)."""
    try:
        return math.isfinite(x)  # type: ignore[arg-type]
    except OverflowError:
        return False


def read_recording(path: str | Path, model: Model, torque_constant: float | None = None, *,
                   ignore_others_of: Model | None = None) -> Recording:
    """Read and validate a recording CSV for a model.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file (columns as the module describes).
    model : Model
        The model whose motors and joints name the columns.
    torque_constant : float, optional
        N m/A: converts ``current_<motor>`` columns to torques; required with them and refused without them.
    ignore_others_of : Model, optional
        A wider model (e.g. the whole robot of a :meth:`~alpes_dyn.model.robot.Model.subtree` ``model``) whose
        columns of motors and joints that ``model`` does not have are accepted and ignored (a recording of the
        whole hand read for one finger; their cells are still numbers, and their encoders within the wider
        model's joint ranges); a column of neither model is still refused.

    Returns
    -------
    Recording

    Raises
    ------
    RecordingError
        Every defect the module lists, one line naming the column (and the row).
    """
    _check_reader(torque_constant, model)
    if ignore_others_of is not None and not isinstance(ignore_others_of, Model):
        raise RecordingError(f"ignore_others_of: expected an alpes_dyn Model or None, got "
                             f"{type(ignore_others_of).__name__}")
    text = _read_text(path)  # (a path that is not a str or os.PathLike: RecordingError, before Path() sees it)
    p = Path(path)
    n_lines = text.count("\n")
    if n_lines > MAX_CSV_ROWS + 1:
        raise RecordingError(f"recording {str(p)!r}: more than {MAX_CSV_ROWS} rows (the limit of a recording)")
    refuse_empty_row(text, p)  # (never skipped: a lost sample)
    # the rows parsed one at a time into the array (a list of every row's cells is many times the array), the
    # lines cut from the text as read (csv_numbers.lines: no copy of the text)
    rows = (r for r in csv.reader(lines(text)) if r and any(c.strip() for c in r))
    header = _header(rows, p, model, ignore_others_of)
    data = plain_rows(text, len(header))  # a logger's plain numbers by NumPy's parser; else cell by cell
    data = _parse_rows(rows, p, header, n_lines) if data is None else data
    del text
    own = _known_columns(model)
    col = {h: data[:, j] for j, h in enumerate(header) if h in own}
    if "t" not in col:
        raise RecordingError("recording: missing column 't' (time, s)")
    motors, joints = model.transmission.motor_names, model.joint_names
    _check_true_columns(col, joints)
    enc, torque = _motor_columns(col, motors, torque_constant, p)
    # every column copied out of the parsed rows (a view would keep them all: 29 MB at 600 s of finger3)
    rec = Recording(t=col["t"].copy(), encoder=np.column_stack(enc), torque=np.column_stack(torque),
                    motor_names=tuple(motors), joint_names=tuple(joints), q=_joint_columns(col, joints, "q"),
                    force_z=col["force_z"].copy() if "force_z" in col else None, gravity=_gravity_columns(col),
                    true_q=_joint_columns(col, joints, "true_q"), run=_run_column(col),
                    held_out=held_out_column(col))
    check_recording(rec)
    check_units(rec, model, "current" if torque_constant is not None else "torque")
    if ignore_others_of is not None:  # the ignored encoders too: a reading far outside is no encoder in counts
        others = {h[len("encoder_"):]: data[:, j] for j, h in enumerate(header)
                  if h not in own and h.startswith("encoder_")}
        _check_encoder_columns(others, ignore_others_of)
    return rec


def _check_reader(torque_constant: float | None, model: Model) -> None:
    """The arguments of :func:`read_recording`: a positive torque constant (N m/A) or None, an alpes_dyn Model."""
    if torque_constant is not None and not (isinstance(torque_constant, (int, float, np.integer, np.floating))
                                            and not isinstance(torque_constant, (bool, np.bool_))
                                            and _finite(torque_constant) and torque_constant > 0):
        raise RecordingError(f"torque_constant: expected a positive number of N m/A, got {torque_constant!r:.60}")
    if torque_constant is not None:  # an absurd one (1e300 N m/A) or a subnormal number
        check_physical(float(torque_constant), "torque_constant", "N m/A", "pos", RecordingError)
    if not isinstance(model, Model):
        raise RecordingError(f"model: expected an alpes_dyn Model (it names the columns), got {type(model).__name__}")


def _read_text(path: str | Path) -> str:
    """The recording's text (UTF-8, a byte-order mark accepted; at most :data:`MAX_RECORDING_BYTES`)."""
    data_bytes = read_bytes(path, "recording", RecordingError, MAX_RECORDING_BYTES)
    try:
        return data_bytes.decode("utf-8-sig")  # a byte-order mark is accepted
    except UnicodeDecodeError:
        raise RecordingError(f"recording {str(Path(path))!r}: not a UTF-8 text file") from None


def _known_columns(model: Model) -> set[str]:
    """The columns a recording of ``model`` may hold (its motors' and joints' names in them)."""
    motors, joints = model.transmission.motor_names, model.joint_names
    known = {"t", "run", "held_out", "force_z", "gravity_x", "gravity_y", "gravity_z"}
    known |= {f"{k}_{mn}" for k in ("encoder", "torque", "current") for mn in motors}
    return known | {f"{k}_{jn}" for k in ("q", "true_q") for jn in joints}


def _header(rows, p: Path, model: Model, wider: Model | None = None) -> list[str]:
    """The column names of the first row of ``rows``: each at most :data:`MAX_CSV_CELL` characters, once, and a
    column of ``model`` (its motors' and joints' names) or of the ``wider`` model."""
    first = _next_row(rows, p)
    if first is None:
        raise RecordingError(f"recording {str(p)!r}: empty file")
    header = [h.strip() for h in first]
    long = next((h for h in header if len(h) > MAX_CSV_CELL), None)
    if long is not None:
        raise RecordingError(f"recording: a column name of {len(long)} characters, over the limit of {MAX_CSV_CELL}")
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise RecordingError(f"recording: column {dup!r} appears twice")
    tr = model.transmission
    if tr is None:
        raise RecordingError(f"recording: model {model.name!r} has no tendon transmission (no motors to read)")
    motors, joints = tr.motor_names, model.joint_names
    known = _known_columns(model)
    if wider is not None and wider.transmission is not None:
        known |= _known_columns(wider)
    for h in header:
        if h not in known:
            raise RecordingError(f"recording: unknown column {h!r} for model {model.name!r} "
                                 f"(motors {', '.join(motors)}; joints {', '.join(joints)})")
    return header


def _parse_rows(rows, p: Path, header: list[str], n_lines: int) -> np.ndarray:
    """The data rows as an array (rows, columns): numbers (no digit separators), empty or NaN cells only in the
    optional measurements (``q_*``, ``force_z``: NaN there; ``true_q_*`` is a simulation's, every sample)."""
    optional_nan = {h for h in header if h.startswith("q_") or h == "force_z"}
    data = np.empty((n_lines + 1, len(header)))  # at least one row per line: trimmed below
    n_rows = 0
    for i in itertools.count(2):
        row = _next_row(rows, p)
        if row is None:
            break
        n_rows += 1
        if len(row) != len(header):
            raise RecordingError(f"recording: line {i} has {len(row)} fields, the header {len(header)}")
        for j, cell in enumerate(row):
            c = cell.strip()
            if len(c) > MAX_CSV_CELL:
                raise RecordingError(f"recording: column {header[j]!r} line {i}: a cell of {len(c)} characters, "
                                     f"over the limit of {MAX_CSV_CELL}")
            if c == "":
                if header[j] not in optional_nan:
                    raise RecordingError(f"recording: column {header[j]!r} is empty at line {i} "
                                         "(only q_* and force_z may have empty cells)")
                data[i - 2, j] = np.nan
                continue
            try:
                if "_" in c:  # Python reads 1_000 as 1000; a CSV number has no digit separators
                    raise ValueError(c)
                data[i - 2, j] = float(c)
            except ValueError:
                raise RecordingError(f"recording: column {header[j]!r} line {i}: not a number ({c!r})") from None
            if not math.isfinite(data[i - 2, j]) and header[j] not in optional_nan:
                raise RecordingError(f"recording: column {header[j]!r} line {i}: NaN or inf")
    data = data[:n_rows]
    tiny = np.argwhere((data != 0) & (np.abs(data) < np.finfo(float).tiny))  # (NaN compares False: not tiny)
    if tiny.size:  # no sensor reads 1e-320: a value written wrong (and its digits are not a float's)
        k, j = (int(x) for x in tiny[0])
        check_not_subnormal(float(data[k, j]), f"recording: column {header[j]!r} line {k + 2}", error=RecordingError)
    return data


def _motor_columns(col: dict[str, np.ndarray], motors: tuple[str, ...], torque_constant: float | None, p: Path
                   ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each motor's encoder (counts) and torque (N m: ``torque_<motor>``, or ``current_<motor>`` A times the
    torque constant), (N,) each; the torque constant refused where no column is a current."""
    enc, torque = [], []
    for mn in motors:
        if f"encoder_{mn}" not in col:
            raise RecordingError(f"recording: missing column 'encoder_{mn}' (counts)")
        enc.append(col[f"encoder_{mn}"])
        has_t, has_c = f"torque_{mn}" in col, f"current_{mn}" in col
        if has_t == has_c:
            raise RecordingError(f"recording: motor {mn!r} needs exactly one of 'torque_{mn}' (N m) and "
                                 f"'current_{mn}' (A)")
        if has_c:
            if torque_constant is None:
                raise RecordingError(f"recording: column 'current_{mn}' needs a torque constant (N m/A: "
                                     "torque_constant, or --torque-constant on the command line)")
            torque.append(float(torque_constant) * col[f"current_{mn}"])
        else:
            torque.append(col[f"torque_{mn}"])
    if torque_constant is not None and not any(f"current_{mn}" in col for mn in motors):
        raise RecordingError(f"recording {str(p)!r}: a torque constant is given but it has no current_<motor> column "
                             f"(its torques are torque_<motor>, N m)")
    return enc, torque


def _run_column(col: dict[str, np.ndarray]) -> np.ndarray | None:
    """The ``run`` column as (N,) integers (None without it): each cell a whole number (``2``, ``2.0``), not
    decreasing (its runs in order, each one contiguous)."""
    if "run" not in col:
        return None
    r = col["run"]
    frac = np.flatnonzero(r != np.round(r))
    if frac.size:
        k = int(frac[0])
        raise RecordingError(f"recording: column 'run' line {k + 2}: {r[k]!r} is not an integer (the run's number)")
    if np.any(np.abs(r) > 2**53):
        k = int(np.argmax(np.abs(r) > 2**53))
        raise RecordingError(f"recording: column 'run' line {k + 2}: {r[k]:g} is beyond the integers a float holds")
    return r.astype(np.int64)


def _check_true_columns(col: dict[str, np.ndarray], joints: tuple[str, ...]) -> None:
    """The true angles ``true_q_<joint>`` for every joint of the model or for none (with some missing, every joint's
    RMSE was silently dropped: the estimate said the file had no true angles)."""
    missing = [jn for jn in joints if f"true_q_{jn}" not in col]
    if len(missing) not in (0, len(joints)):
        raise RecordingError(f"recording: true_q_* has no column for joint{'s' if len(missing) > 1 else ''} "
                             f"{', '.join(repr(j) for j in missing[:5])}: the true angles of every joint, or none")


def _joint_columns(col: dict[str, np.ndarray], joints: tuple[str, ...], prefix: str) -> np.ndarray | None:
    """The columns ``<prefix>_<joint>`` as (N, n) rad (NaN for a joint without a column), or None without any."""
    names = [f"{prefix}_{jn}" for jn in joints]
    present = [n for n in names if n in col]
    if not present:
        return None
    return np.column_stack([col[n] if n in col else np.full(len(col["t"]), np.nan) for n in names])


def _gravity_columns(col: dict[str, np.ndarray]) -> np.ndarray | None:
    """The gravity columns as (N, 3) m/s^2, None without them; all three or none."""
    grav_cols = [f"gravity_{a}" for a in "xyz"]
    present = [g for g in grav_cols if g in col]
    if present and len(present) != 3:
        raise RecordingError(f"recording: gravity needs all three columns gravity_x, gravity_y, gravity_z "
                             f"(got {', '.join(present)})")
    return np.column_stack([col[g] for g in grav_cols]) if present else None


def _check_runs(rec: Recording, N: int) -> np.ndarray:
    """The ``run`` column of ``rec`` (None, or (N,) integers not decreasing, each run at least :data:`MIN_SAMPLES`
    samples); returns :meth:`Recording.run_starts`."""
    if rec.run is None:
        return np.array([0, N])
    r = np.asarray(rec.run)
    if r.shape != (N,) or not (np.issubdtype(r.dtype, np.integer)
                                or (np.issubdtype(r.dtype, np.floating) and np.all(r == np.round(r)))):
        raise RecordingError(f"recording: run has shape {r.shape} and type {r.dtype}, expected ({N},) integers")
    down = np.flatnonzero(np.diff(r) < 0)
    if down.size:
        k = int(down[0]) + 1
        raise RecordingError(f"recording: column 'run' decreases at line {k + 2} ({int(r[k - 1])} then {int(r[k])}): "
                             "each run's samples together, the runs in order")
    b = rec.run_starts()
    short = np.flatnonzero(np.diff(b) < MIN_SAMPLES)
    if short.size:
        j = int(short[0])
        raise RecordingError(f"recording: run {int(r[b[j]])} (from line {b[j] + 2}) has {int(b[j + 1] - b[j])} "
                             f"samples; each run needs at least {MIN_SAMPLES}")
    return b


def check_recording(rec: Recording) -> Recording:
    """Validate a :class:`Recording` (shapes, time, units, length, excitation); returns it."""
    t = np.asarray(rec.t, dtype=float)
    N = t.shape[0]
    if t.ndim != 1 or N < MIN_SAMPLES:
        raise RecordingError(f"recording: too short ({N} samples; at least {MIN_SAMPLES} are needed)")
    m, n = len(rec.motor_names), len(rec.joint_names)
    for name, a, shape in (("encoder", rec.encoder, (N, m)), ("torque", rec.torque, (N, m)),
                           ("q", rec.q, (N, n)), ("true_q", rec.true_q, (N, n)), ("force_z", rec.force_z, (N,)),
                           ("gravity", rec.gravity, (N, 3))):
        if a is not None and np.shape(a) != shape:
            raise RecordingError(f"recording: {name} has shape {np.shape(a)}, expected {shape}")
    for name, a in (("t", t), ("encoder", rec.encoder), ("torque", rec.torque), ("gravity", rec.gravity)):
        if a is not None and not np.isfinite(a).all():
            raise RecordingError(f"recording: {name} contains NaN or inf")
    b = _check_runs(rec, N)
    check_held_out(rec.held_out, b, MIN_SAMPLES)
    dts = np.diff(t)
    within = np.ones(N - 1, dtype=bool)
    within[b[1:-1] - 1] = False  # the step from a run's last sample to the next one's first is no period
    if np.any((dts <= 0) & within):
        k = int(np.argmax((dts <= 0) & within))
        raise RecordingError(f"recording: t is not strictly increasing (row {k + 2}: {t[k + 1]!r} after {t[k]!r})")
    dt = float(np.sum(t[b[1:] - 1] - t[b[:-1]]) / (N - (len(b) - 1)))  # the period within the runs
    # tolerance: 1e-6 of the period, or the float resolution of the time stamps (Unix-epoch times, ~1.7e9 s,
    # hold only ~0.24 us: their steps jitter by that much)
    off = np.where(within, np.abs(dts - dt), 0.0)
    if np.max(off) > 1e-6 * dt + 1e-12 + 4 * float(np.spacing(np.max(np.abs(t)))):
        k = int(np.argmax(off))
        where = "" if len(b) == 2 else f" (run {int(rec.run[k])}: every run at the one sample period)"
        raise RecordingError(f"recording: t is not uniformly sampled (step {dts[k]:g} s at row {k + 2}, "
                             f"mean {dt:g} s){where}")
    if not 1e-6 <= dt <= 0.1:
        unit = next((u for u, f in (("milliseconds", 1e-3), ("microseconds", 1e-6)) if 1e-6 <= dt * f <= 0.1), None)
        raise RecordingError(f"recording: sample period {dt:g} s is outside [1e-6, 0.1] s"
                             + (f": t in {unit}? the recording's time is in s" if unit and dt > 0.1 else
                                " (is t in seconds?)"))
    resolution = float(np.spacing(np.max(np.abs(t))))
    if resolution > 1e-3 * dt:  # Unix-epoch seconds (1.7e9: 2.4e-7 s) hold a 1 ms period; 1e12 s does not
        raise RecordingError(f"recording: t reaches {np.max(np.abs(t)):g} s, where a float holds time only to "
                             f"{resolution:.2g} s, over 1e-3 of the sample period {dt:g} s: subtract the start time")
    for name, a in (("q", rec.q), ("true_q", rec.true_q)):
        if a is not None and np.nanmax(np.abs(a), initial=0.0) > 2 * np.pi:
            raise RecordingError(f"recording: {name}_* exceeds 2 pi in magnitude: joint angles must be in rad, "
                                 "not degrees")
    if rec.gravity is not None:
        bad = gravity_norm_off(rec.gravity)
        if bad.size:
            k = int(bad[0])
            raise RecordingError(f"recording: gravity has norm {np.linalg.norm(rec.gravity[k]):g} m/s^2 at row {k + 2}; "
                                 f"expected {GRAVITY:g} m/s^2 within {100 * GRAVITY_TOLERANCE:g} % (m/s^2, not units of g)")
    enc = np.asarray(rec.encoder, dtype=float)
    if np.all(np.ptp(enc, axis=0) < 2) and np.all(np.ptp(np.asarray(rec.torque), axis=0) == 0):
        raise RecordingError("recording: no excitation (the torque is constant and no encoder moves)")
    return rec


def join_runs(recordings: "list[Recording] | tuple[Recording, ...]") -> Recording:
    """One :class:`Recording` of several runs: ``recordings`` (of one model, at one sample period) one after
    the other, each its own run (``run`` 0, 1, ...; a recording that has runs already keeps them apart, numbered
    on), each its own time. Raises :class:`~alpes_dyn.errors.RecordingError` for recordings that do not go together
    (other motors or joints, optional columns in some only, another sample period).

    Parameters
    ----------
    recordings : list or tuple of Recording
        The runs, in order.

    Returns
    -------
    Recording
    """
    recs = list(recordings)
    if not recs or not all(isinstance(r, Recording) for r in recs):
        raise RecordingError("join_runs: expected one or more Recordings")
    first = recs[0]
    for r in recs[1:]:
        if r.motor_names != first.motor_names or r.joint_names != first.joint_names:
            raise RecordingError(f"join_runs: motors {r.motor_names} / joints {r.joint_names} differ from the first "
                                 f"recording's {first.motor_names} / {first.joint_names}")
        if abs(r.dt - first.dt) > 1e-6 * first.dt:
            raise RecordingError(f"join_runs: sample period {r.dt:g} s differs from the first recording's "
                                 f"{first.dt:g} s")
    cols = {}
    for name in ("t", "encoder", "torque", "q", "force_z", "gravity", "true_q"):
        parts = [getattr(r, name) for r in recs]
        if all(p is None for p in parts):
            cols[name] = None
        elif any(p is None for p in parts):
            raise RecordingError(f"join_runs: {name} is in some of the recordings only")
        else:
            cols[name] = np.concatenate(parts)
    held = [r.held_out for r in recs]  # a recording without the column: none of its samples held out
    cols["held_out"] = None if all(h is None for h in held) else np.concatenate(
        [np.zeros(r.n_samples, bool) if h is None else np.asarray(h, bool) for r, h in zip(recs, held)])
    run, base = [], 0
    for r in recs:  # a loop over the recordings (a few)
        own = np.repeat(np.arange(r.n_runs), np.diff(r.run_starts()))
        run.append(base + own)
        base += r.n_runs
    return check_recording(Recording(motor_names=first.motor_names, joint_names=first.joint_names,
                                     run=np.concatenate(run), **cols))
