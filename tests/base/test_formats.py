"""read_versioned_npz: every way a file can be wrong is a FileFormatError or FormatVersionError."""

from __future__ import annotations

import io

import numpy as np
import pytest

from terrawatt_base.errors import FileFormatError, FormatVersionError
from terrawatt_base.formats import check_format_version, read_versioned_npz

MAGIC = "terrawatt-test"


def _npz(path, **arrays):
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    return path


def test_reads_a_good_file(tmp_path):
    path = _npz(tmp_path / "ok.npz", __magic__=np.array(MAGIC), __version__=np.array(3), a=np.arange(4))
    content = read_versioned_npz(path, magic=MAGIC, version=3, what="thing")
    np.testing.assert_array_equal(content["a"], np.arange(4))


def test_truncated_and_foreign_files_are_format_errors(tmp_path):
    buf = io.BytesIO()
    np.savez_compressed(buf, __magic__=np.array(MAGIC), __version__=np.array(3), a=np.random.default_rng(0).random(5000))
    data = buf.getvalue()
    for i, cut in enumerate((len(data) // 2, len(data) - 30, 40)):
        path = tmp_path / f"cut{i}.npz"
        path.write_bytes(data[:cut])
        with pytest.raises(FileFormatError, match="corrupt or not a .npz"):
            read_versioned_npz(path, magic=MAGIC, version=3, what="thing")
    npy = tmp_path / "array.npz"
    with open(npy, "wb") as fh:
        np.save(fh, np.zeros(3))  # a .npy under a .npz name
    with pytest.raises(FileFormatError, match="corrupt or not a .npz"):
        read_versioned_npz(npy, magic=MAGIC, version=3, what="thing")
    with pytest.raises(FileFormatError, match="missing"):
        read_versioned_npz(tmp_path / "absent.npz", magic=MAGIC, version=3, what="thing")
    other = _npz(tmp_path / "other.npz", __magic__=np.array("someone-else"), __version__=np.array(3))
    with pytest.raises(FileFormatError, match="not a terrawatt thing"):
        read_versioned_npz(other, magic=MAGIC, version=3, what="thing")


def test_versions(tmp_path):
    newer = _npz(tmp_path / "newer.npz", __magic__=np.array(MAGIC), __version__=np.array(4))
    with pytest.raises(FormatVersionError, match="format version 4; this terrawatt reads version 3"):
        read_versioned_npz(newer, magic=MAGIC, version=3, what="thing")
    none = _npz(tmp_path / "none.npz", __magic__=np.array(MAGIC))
    with pytest.raises(FileFormatError, match="no valid format version"):
        read_versioned_npz(none, magic=MAGIC, version=3, what="thing")
    with pytest.raises(FileFormatError, match="no valid format version"):
        check_format_version("three", 3, "thing", "x.json")
    assert check_format_version(3, 3, "thing", "x.json") == 3
