"""The output folder: spec.json (whose rows the folder holds), batches/ (one CSV per finished batch,
written under a temporary name and renamed, so a file under its own name is never cut), results.csv
(the batches concatenated) and what a restart finds there: each batch file checked against what this
sweep would write before its rows are taken. Input files (the spec, a batch) are read only when
they are regular files, and only up to a bound."""

import contextlib
import csv
import io
import json
import math
import os
import re
import stat

import numpy as np

from ._sweep_errors import OutputError, _error, _excerpt, _one_line, _say


# A batch file is read (on resume) only up to its header and this much a row: a row as written
# is at most about 6 KB (a run's name of 200 characters and a reason of 500, quoted, in UTF-8)
# and 25 bytes a number.
MAX_ROW_BYTES, MAX_CELL_BYTES = 8192, 32


def _cell(value):
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)  # round-trip exact: a restarted sweep writes the same bytes
    return str(value)


def _csv_text(header, rows):
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")  # quotes what needs quoting (commas, quotes, newlines)
    if header is not None:
        writer.writerow(header)
    writer.writerows([[_cell(v) for v in row] for row in rows])
    return buffer.getvalue()


@contextlib.contextmanager
def _atomic_output(path):
    """A text file written under a temporary name beside `path`, synced and renamed to it when the
    block ends: a file under its own name is never cut. A failed write removes the temporary and
    raises OutputError naming `path`; any other error in the block removes it too."""
    temp = os.path.join(os.path.dirname(path), f".{os.path.basename(path)}.{os.getpid()}.tmp")
    try:
        with open(temp, "w", encoding="utf-8", newline="") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(temp, path)
    except BaseException as e:
        with contextlib.suppress(OSError):
            os.unlink(temp)
        if isinstance(e, OSError):
            raise OutputError(f"{path}: writing failed: {e.strerror or e}") from None
        raise


def _write_atomically(path, text):
    with _atomic_output(path) as f:
        f.write(text)


def _remove(path):
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass
    except OSError as e:
        raise OutputError(f"{path}: cannot remove it: {e.strerror or e}") from None


# A batch's file: its variants are first..last, every one of them (batches never span a gap).
_BATCH_FILE = re.compile(r"^rows-(\d+)-(\d+)\.csv$")


def _parse_cell(text, column):
    if column in ("run", "stopped"):
        return text
    if column == "complete":
        return text == "true"
    if column == "variant":
        return int(text)
    return float(text) if text != "" else None


class _Refused(Exception):
    """An input file that is not read, or not taken: the reason."""


def _kind(mode):
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "of another kind"


def _open_regular(path, limit=None):
    """`path` opened for reading (binary) if it is a regular file (through links) of at most
    `limit` bytes, else _Refused with the reason. A FIFO, a device (/dev/zero) or a folder is
    refused before anything is read from it, so nothing waits for a writer or reads without end:
    checked by stat, then opened non-blocking and checked again (it may have been swapped)."""
    try:
        if not stat.S_ISREG(mode := os.stat(path).st_mode):
            raise _Refused(f"not a regular file ({_kind(mode)})")
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError as e:
        raise _Refused(f"cannot read: {e.strerror or e}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise _Refused(f"not a regular file ({_kind(st.st_mode)})")
        if limit is not None and st.st_size > limit:
            raise _Refused(f"larger than {limit} bytes")
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def _read_bounded(path, limit):
    """A regular file's bytes, at most `limit` (_Refused beyond, also when it grows while read)."""
    with _open_regular(path, limit) as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise _Refused(f"larger than {limit} bytes")
    return data


def _csv_rows(f, limit):
    """A CSV file's rows (UTF-8), read line by line and at most `limit` bytes in all (_Refused
    beyond: a line without end is not read whole). UnicodeDecodeError and csv.Error as they come."""

    def lines():
        left = limit
        while line := f.readline(left + 1):
            left -= len(line)
            if left < 0:
                raise _Refused(f"larger than {limit} bytes")
            yield line.decode("utf-8")  # a line ends at b"\n", never inside a UTF-8 sequence

    return csv.reader(lines())


def _batch_limit(header, rows):
    return len(_csv_text(header, [])) + rows * (MAX_ROW_BYTES + MAX_CELL_BYTES * len(header))


def _is_number(text):
    """A finite number in its round-trip form (Python's repr), as the sweep writes one."""
    try:
        value = float(text)
    except ValueError:
        return False
    return math.isfinite(value) and repr(value) == text


def _check_batch(path, first, last, plan, header, keep):
    """A batch file found on resume, checked against what this sweep writes there: the header, one
    row per variant first..last and run in that order, each row's variant id and parameter values
    to the bit and its run's name, `complete` true or false (a complete row stopped for no
    reason), a reason of one line, every number finite and round-trip exact, reach_failure 0 or 1,
    and no row more. Returns the rows, parsed (keep), else None; _Refused with the first problem.
    (A number edited to another finite one in its exact form is not found: the file has no
    checksum.)"""
    variants = plan.values[first:last + 1].tolist()
    rows = (last - first + 1) * len(plan.runs)
    p = len(plan.names)
    kept = [] if keep else None
    count = 0
    try:
        with _open_regular(path, _batch_limit(header, rows)) as f:
            reader = _csv_rows(f, _batch_limit(header, rows))
            if next(reader, None) != header:
                raise _Refused("its header is not this sweep's columns" if f.tell() else "empty")
            for k, row in enumerate(reader):
                count = k + 1
                where = f"row {k + 1}"
                if k >= rows:
                    raise _Refused(f"more than its {rows} rows ({last - first + 1} variants x {len(plan.runs)} runs)")
                if len(row) != len(header):
                    raise _Refused(f"{where}: {len(row)} cells, not {len(header)}")
                v, r = divmod(k, len(plan.runs))
                expected = [str(first + v), *map(_cell, variants[v]), plan.runs[r][0]]
                for column, (cell, want) in enumerate(zip(row, expected)):
                    if cell != want:
                        raise _Refused(f"{where}, {header[column]}: {_excerpt(cell)} where this sweep has {_excerpt(want)}")
                complete, stopped = row[p + 2], row[p + 3]
                if complete not in ("true", "false") or (complete == "true" and stopped) or len(stopped) > 500:
                    raise _Refused(f"{where}: complete {_excerpt(complete)}, stopped {_excerpt(stopped)} is not a row "
                                   "the sweep writes")
                for column in range(p + 4, len(header)):
                    cell = row[column]
                    if header[column] == "reach_failure":
                        good = cell in ("0", "1")
                    else:
                        good = _is_number(cell) or (cell == "" and column > p + 4)  # t_end is always there
                    if not good:
                        raise _Refused(f"{where}, {header[column]}: {_excerpt(cell)} is not a finite number as the sweep writes one")
                if keep:
                    kept.append([_parse_cell(c, h) for c, h in zip(row, header)])
    except UnicodeDecodeError:
        raise _Refused("not UTF-8 text") from None
    except csv.Error as e:
        raise _Refused(f"not CSV as the sweep writes it ({_one_line(e, 200)})") from None
    if count < rows:
        raise _Refused(f"{count} rows, not its {rows} ({last - first + 1} variants x {len(plan.runs)} runs)")
    return kept


def _claim(out, plan):
    """The output folder `out` made ready for this sweep: its batches/ folder created, and spec.json
    (what must match for a restart to reuse written rows, _Plan.identity) written, or compared when
    it is there: a folder that holds another sweep's rows is an error. Returns the batches' folder."""
    batches_dir = os.path.join(out, "batches")
    try:
        os.makedirs(batches_dir, exist_ok=True)
    except OSError as e:
        raise OutputError(f"{out}: cannot create the folder: {e.strerror or e}") from None
    identity = json.dumps(plan.identity(), sort_keys=True)
    identity_path = os.path.join(out, "spec.json")
    if os.path.lexists(identity_path):
        try:  # read no more than this sweep's own identity and a byte: more is another sweep's
            with _open_regular(identity_path) as f:
                same = f.read(len(identity.encode()) + 1) == identity.encode()
        except _Refused as e:
            _error("out", f"{identity_path}: {e}")
        if not same:
            _error("out", f"{out} holds the rows of another sweep (another model, parameters, runs or metrics): "
                          "remove it or give another folder")
    else:
        _write_atomically(identity_path, identity)
    return batches_dir


def _resume(out, plan, header, keep):
    """What the output folder `out` already holds of this sweep (a killed sweep's batches, each
    checked), the folder made ready for the rest (_claim): (the batches' folder, done: a bool per
    variant, kept: variant -> its rows (keep), files). Without `out`: nothing is written yet."""
    n = len(plan.values)
    done = np.zeros(n, dtype=bool)
    kept = {}  # variant -> its rows (keep=True)
    files = []  # (first, last, path) of every batch file
    if out is None:
        return None, done, kept, files
    batches_dir = _claim(out, plan)
    for name in sorted(os.listdir(batches_dir)):
        path = os.path.join(batches_dir, name)
        m = _BATCH_FILE.match(name)
        if name.startswith(".") and name.endswith(".tmp"):
            _remove(path)  # a batch being written when the sweep was killed: it runs again
        elif m:
            first, last = int(m[1]), int(m[2])
            if not 0 <= first <= last < n or done[first:last + 1].any():
                _error("out", f"{path}: not a batch of this sweep (variants {first}..{last} of {n})")
            # Not a file the sweep wrote there (a FIFO, a device, a folder): not read, and not
            # removed either: someone put it there.
            try:
                mode = os.stat(path).st_mode
            except OSError as e:
                _error("out", f"{path}: cannot read: {e.strerror or e}")
            if not stat.S_ISREG(mode):
                _error("out", f"{path}: not a regular file ({_kind(mode)}): remove it and run the same sweep again")
            # Its rows are taken only as this sweep would write them; a file cut, edited or
            # holding a row more runs again (README.md, "Killed, then resumed").
            try:
                rows = _check_batch(path, first, last, plan, header, keep)
            except _Refused as e:
                _say(f"sweep: {path}: {e}; its variants {first}..{last} run again\n")
                _remove(path)
                continue
            if keep:
                for row in rows:
                    kept.setdefault(row[0], []).append(row)
            done[first:last + 1] = True
            files.append((first, last, path))
    return batches_dir, done, kept, files


def _concatenate(files, header, path, runs):
    """results.csv: the batch files' rows in variant order (each file holds one range, in order),
    streamed to a temporary name and renamed. Returns (rows that completed, rows)."""
    complete_column = header.index("complete")
    complete = total = 0
    with _atomic_output(path) as out:
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(header)
        for first, last, batch in files:  # each checked on resume, or written by this sweep
            try:
                with _open_regular(batch) as f:
                    reader = _csv_rows(f, _batch_limit(header, (last - first + 1) * runs))
                    next(reader)
                    for row in reader:
                        writer.writerow(row)
                        total += 1
                        complete += row[complete_column] == "true"
            except _Refused as e:
                _error("out", f"{batch}: {e}")
    return complete, total
