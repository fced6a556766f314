"""read_versioned_npz and the result JSON codec: every way a file can be wrong is a FileFormatError."""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest

from terrawatt_base.errors import FileFormatError, FormatVersionError, InvalidParameterError
from terrawatt_base.formats import (
    RESULT_JSON_INDENT,
    check_format_version,
    format_name,
    read_result_json,
    read_versioned_npz,
    result_document,
    write_result_json,
)

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


# ------------------------------------------------------------------ result JSON documents
def test_a_result_document_opens_with_its_format_and_version():
    doc = result_document("thing", 3, {"energy_j": 1.5, "rows": [1, 2]})
    assert doc == {"format": "terrawatt-thing", "format_version": 3, "energy_j": 1.5, "rows": [1, 2]}
    assert list(doc)[:2] == ["format", "format_version"]
    assert format_name("route") == "terrawatt-route"


def test_bad_kinds_versions_and_bodies_are_refused():
    for kind in ("", "terrawatt-thing", " thing", 3):
        with pytest.raises(InvalidParameterError, match="kind must be a non-empty name"):
            result_document(kind, 1, {})
    for version in (0, -1, 1.0, True, "1", None):
        with pytest.raises(InvalidParameterError, match="version must be an int >= 1"):
            result_document("thing", version, {})
    with pytest.raises(InvalidParameterError, match=r"must not hold \['format_version'\]"):
        result_document("thing", 1, {"format_version": 2})


def test_written_json_is_strict_with_nan_and_inf_as_null_and_numpy_as_plain(tmp_path):
    body = {"nan": math.nan, "inf": [math.inf, -math.inf, 1.0], "array": np.arange(3), "scalar": np.float32(0.5),
            "nested": {"x": (np.int64(2), math.nan)}, "text": "é"}
    path = write_result_json(tmp_path / "sub" / "r.json", result_document("thing", 2, body))
    text = path.read_text(encoding="utf-8")
    assert text.endswith("}\n") and "NaN" not in text and "Infinity" not in text
    assert text.startswith('{\n' + " " * RESULT_JSON_INDENT + '"format": "terrawatt-thing",')
    data = json.loads(text)
    assert data == {"format": "terrawatt-thing", "format_version": 2, "nan": None, "inf": [None, None, 1.0],
                    "array": [0, 1, 2], "scalar": 0.5, "nested": {"x": [2, None]}, "text": "é"}
    assert read_result_json(path, "thing", 2) == data
    assert [p.name for p in path.parent.iterdir()] == ["r.json"]  # no temporary left



def test_an_integer_past_pythons_digit_limit_is_a_format_error(tmp_path):
    # found by benchmarks/fuzz_readers.py (the robot-file kind): json raised a bare ValueError
    path = tmp_path / "long.json"
    path.write_text('{"format": "terrawatt-thing", "format_version": 2, "n": ' + "9" * 5000 + "}")
    with pytest.raises(FileFormatError, match=r"long.json.* is corrupt: it holds an integer of more than 4300 digits"):
        read_result_json(path, "thing", 2)
    path.write_text('{"format": "terrawatt-thing", "format_version": ' + "1" * 4301 + "}")
    with pytest.raises(FileFormatError, match="more than 4300 digits"):
        read_result_json(path, "thing", 2, what="robot")

def test_only_documents_are_written(tmp_path):
    with pytest.raises(InvalidParameterError, match="needs a 'format' starting with 'terrawatt-'"):
        write_result_json(tmp_path / "a.json", {"format_version": 1, "x": 1})
    with pytest.raises(InvalidParameterError, match="needs a 'format'"):
        write_result_json(tmp_path / "a.json", {"format": "someone-else", "format_version": 1})
    with pytest.raises(InvalidParameterError, match="version must be an int"):
        write_result_json(tmp_path / "a.json", {"format": "terrawatt-thing"})
    with pytest.raises(InvalidParameterError, match="cannot be written as JSON"):
        write_result_json(tmp_path / "a.json", result_document("thing", 1, {"x": object()}))
    assert not (tmp_path / "a.json").exists()


def test_reading_back_foreign_wrong_kind_newer_and_corrupt_files(tmp_path):
    good = write_result_json(tmp_path / "good.json", result_document("thing", 2, {"x": 1}))
    with pytest.raises(FileFormatError, match="terrawatt other .format 'terrawatt-thing', expected 'terrawatt-other'"):
        read_result_json(good, "other", 2)  # another terrawatt kind
    with pytest.raises(FormatVersionError, match="format version 2; this terrawatt reads version 1"):
        read_result_json(good, "thing", 1)
    newer = tmp_path / "newer.json"
    newer.write_text(json.dumps({"format": "terrawatt-thing", "format_version": 3}))
    with pytest.raises(FormatVersionError, match="newer.json.*format version 3; this terrawatt reads version 2"):
        read_result_json(newer, "thing", 2, what="thing summary")
    cases = {
        "foreign.json": (json.dumps({"type": "FeatureCollection"}), "is not a terrawatt thing .format None"),
        "list.json": ("[1, 2]", "is not a terrawatt thing"),
        "bad.json": ("{ truncated", "corrupt .not JSON."),
        "binary.json": (b"\xff\xfe\x00", "corrupt"),
        "noversion.json": (json.dumps({"format": "terrawatt-thing"}), "no valid format version"),
        "textversion.json": (json.dumps({"format": "terrawatt-thing", "format_version": "two"}), "no valid format"),
    }
    for name, (content, message) in cases.items():
        path = tmp_path / name
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        with pytest.raises(FileFormatError, match=message):
            read_result_json(path, "thing", 2)
    with pytest.raises(FileFormatError, match="thing file .*absent.json.* is missing"):
        read_result_json(tmp_path / "absent.json", "thing", 2)
    with pytest.raises(FileFormatError, match="is missing"):
        read_result_json(tmp_path, "thing", 2)  # a folder
