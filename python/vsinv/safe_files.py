"""Files read and written by the Python layer, with the rules of the Rust side
(``vsinv::input_file``): an input file must be a regular file (no device, FIFO or directory)
below a size limit, opened without blocking and read with a bound, and an error names the
file and what is wrong, never its contents. Output files are written to a temporary name in
the destination's folder and renamed over it: a symbolic link planted at the destination is
replaced, not followed, and a failed write leaves no partial file."""

from __future__ import annotations

import io
import os
import stat
import tempfile
from pathlib import Path
from typing import IO, Callable, Union

from ._core import InvalidInput

__all__ = ["MAX_CSV_BYTES", "read_text", "replace_file", "replace_text_file"]

_PathLike = Union[str, "os.PathLike[str]"]

#: The largest points CSV, bytes (a million dots take about 30 MB).
MAX_CSV_BYTES = 64 << 20


def read_text(path: _PathLike, limit: int) -> str:
    """The UTF-8 text of the regular file ``path`` (at most ``limit`` bytes); anything else
    raises ``InvalidInput`` naming the file."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as e:
        raise InvalidInput(f"{os.fsdecode(path)}: cannot read: {e.strerror}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise InvalidInput(f"{os.fsdecode(path)}: not a regular file (a directory, device, FIFO or socket)")
        if st.st_size > limit:
            raise InvalidInput(f"{os.fsdecode(path)}: {st.st_size} bytes, more than the limit of {limit} bytes")
    except BaseException:
        os.close(fd)
        raise
    with os.fdopen(fd, "rb") as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise InvalidInput(f"{os.fsdecode(path)}: more than the limit of {limit} bytes")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise InvalidInput(
            f"{os.fsdecode(path)}: not UTF-8 text (invalid byte at offset {e.start}): "
            "a binary file or another encoding (UTF-16, Latin-1)"
        ) from None


def replace_file(path: _PathLike, write: Callable[[IO[bytes]], object]) -> Path:
    """Calls ``write`` with a binary file open at a temporary name beside ``path``, then
    renames it over ``path`` (module docs); returns ``path``."""
    out = Path(path)
    fd, temp = tempfile.mkstemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.chmod(temp, 0o666 & ~_UMASK)
        os.replace(temp, out)
    except BaseException:
        Path(temp).unlink(missing_ok=True)
        raise
    return out


def replace_text_file(path: _PathLike, write: Callable[[IO[str]], object]) -> Path:
    """:func:`replace_file` for text (UTF-8, newlines as written: for ``csv``)."""

    def write_text(f: IO[bytes]) -> None:
        text = io.TextIOWrapper(f, encoding="utf-8", newline="")
        write(text)
        text.flush()
        text.detach()  # the caller closes f

    return replace_file(path, write_text)


def _read_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


# Read once, at import: os.umask is process-wide, so reading it later could race a thread.
_UMASK = _read_umask()
