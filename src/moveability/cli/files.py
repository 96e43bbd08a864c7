"""Output files of the commands: checked before any computation, written whole.

Every output path a command takes (``--out``, ``--json``, ``--figure``) is
checked first, so that a long analysis or sweep never ends on a path that
cannot be written: :func:`check_file` and :func:`check_folder` refuse it in
one line naming the option (exit 2). Files are then written under a
temporary name in the same folder and renamed at the end
(:func:`written_whole`), so that an interrupted command (Ctrl-C included)
leaves either the old file or the new one, never part of one.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

from ..errors import InputError

__all__ = ["check_file", "check_folder", "folder_written_whole", "written_whole"]


def _probe(folder: str, option: str, path: str) -> None:
    """Refuse unless a file can be created in ``folder`` (tried, then removed)."""
    try:
        handle, probe = tempfile.mkstemp(dir=folder, prefix=".moveability-probe-")
    except OSError as error:
        reason = error.strerror or str(error)
        raise InputError(f"invalid {option}: cannot write {path}: {reason}") from None
    os.close(handle)
    os.unlink(probe)


def check_file(path: str, option: str, overwrite: bool, suffixes: Iterable[str] = ()) -> None:
    """Refuse a file that cannot be written: a folder, an existing file without
    ``overwrite``, a missing or read-only folder, or a suffix not in ``suffixes``.

    Examples
    --------
    >>> check_file("/nonexistent/d/x.png", "--out", False)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    moveability.errors.InputError: invalid --out: cannot write ...: no folder /nonexistent/d
    """
    allowed = tuple(suffixes)
    if allowed and not path.lower().endswith(allowed):
        raise InputError(f"invalid {option}: expected a {' or '.join(allowed)} file, got {path!r}")
    if os.path.isdir(path):
        raise InputError(f"invalid {option}: {path} is a folder, expected a file")
    if os.path.lexists(path) and not overwrite:
        raise InputError(f"refusing to overwrite {path}: it exists (use --overwrite)")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise InputError(f"invalid {option}: cannot write {path}: no folder {folder}")
    _probe(folder, option, path)


def check_folder(path: str, option: str, overwrite: bool, names: Iterable[str] = ()) -> None:
    """Refuse a folder that cannot be written into: a file, a folder that holds one
    of ``names`` (without ``overwrite``), or one that cannot be created or written.

    A missing folder is fine when its nearest existing parent is writable: it is
    created at the end, when the files are written.
    """
    if os.path.exists(path) and not os.path.isdir(path):
        raise InputError(f"invalid {option}: {path} is a file, expected a folder")
    if os.path.isdir(path):
        if not overwrite:
            for name in names:
                if os.path.lexists(os.path.join(path, name)):
                    taken = os.path.join(path, name)
                    raise InputError(f"refusing to overwrite {taken}: it exists (use --overwrite)")
        _probe(path, option, path)
        return
    parent = _existing_parent(path)
    if not os.path.isdir(parent):
        raise InputError(f"invalid {option}: cannot create {path}: {parent} is a file")
    _probe(parent, option, path)


def _existing_parent(path: str) -> str:
    """The nearest existing folder above ``path``."""
    parent = os.path.dirname(os.path.abspath(path))
    while not os.path.exists(parent):
        parent = os.path.dirname(parent)
    return parent


@contextmanager
def written_whole(path: str) -> Iterator[str]:
    """A temporary path (same folder, same suffix) to write instead of ``path``;
    renamed to ``path`` when the block ends normally, removed otherwise."""
    folder = os.path.dirname(os.path.abspath(path))
    suffix = os.path.splitext(path)[1]
    temporary = os.path.join(folder, f".moveability-{os.urandom(6).hex()}{suffix}")
    # created as open() would: its mode follows the umask
    os.close(os.open(temporary, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
    try:
        yield temporary
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)


@contextmanager
def folder_written_whole(path: str) -> Iterator[str]:
    """A temporary folder to write the files of ``path`` into; when the block ends
    normally, ``path`` is created if missing and each file is moved into it
    (replacing one of the same name), else the temporary folder is removed."""
    parent = _existing_parent(path)
    temporary = tempfile.mkdtemp(dir=parent, prefix=".moveability-")
    try:
        yield temporary
        os.makedirs(path, exist_ok=True)
        for name in sorted(os.listdir(temporary)):
            os.replace(os.path.join(temporary, name), os.path.join(path, name))
    finally:
        shutil.rmtree(temporary, ignore_errors=True)
