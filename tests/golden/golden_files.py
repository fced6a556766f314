"""Golden-file comparison: what of an output is compared, the one masking rule, readable diffs, regeneration.

An output file is turned into *members* (name -> bytes) before it is compared:

- ``.json`` / ``.geojson``: the text as written, with the values of :data:`MASKED_KEYS` replaced by
  :data:`MASK` in the text itself (nothing is parsed and re-written: indentation, key order and the
  float text are compared as written);
- ``.csv``: the text as written, the cells of a :data:`MASKED_KEYS` column replaced by :data:`MASK`;
- ``.zip`` / ``.npz`` archives: each member, compared apart (a model file's zip container embeds the
  time it was written); a JSON member is masked as above, an ``.npy`` member named after a masked key
  is replaced by :data:`MASK`;
- ``.png`` figures: the decoded pixels (shape and SHA-256 of the RGBA array), not the PNG bytes (whose
  metadata names the matplotlib version), all figures of a case in one ``figures.json``;
- ``.mcap`` ROS 2 bags: the messages they hold, as JSON (``<name>.messages.json``; the route's summary
  message carries a planning time), masked as above;
- any other file (``.md``, ``.yaml``, ``.pgm``, ``.tif``): its bytes;
- an output larger than :data:`DIGEST_OVER_BYTES`, or named in ``golden_cases.DIGESTED``: its digest.

The golden copy of output ``<case>/<name>`` is ``data/<case>/<name>`` (an archive's members under
``data/<case>/<name>/``). Setting ``TERRAWATT_REGEN_GOLDEN=1`` (or running ``regenerate.py``) rewrites
them instead of comparing.
"""

from __future__ import annotations

import csv
import dataclasses
import difflib
import fnmatch
import hashlib
import io
import json
import os
import re
import shutil
import zipfile
from pathlib import Path
from urllib.parse import quote

import numpy as np

__all__ = ["GOLDEN", "MASK", "DIGEST_OVER_BYTES", "MASKED_KEYS", "REGEN_ENV", "MASKED_PRINTED", "MASKED_PRINTED_COLUMNS",
           "check_case", "mask_printed_text", "members", "regenerating", "write_case"]

GOLDEN = Path(__file__).resolve().parent / "data"
REGEN_ENV = "TERRAWATT_REGEN_GOLDEN"
MASK = "<masked>"

#: The fields that legitimately differ between two runs on the same inputs, and nothing else:
#: wall-clock timings (and the rate derived from one) and the package versions a model file records.
MASKED_KEYS = frozenset({
    # wall-clock seconds, measured around the work
    "computing_time_s",  # mission.json
    "elapsed_s",  # batch.json, monte_carlo.json
    "fit_duration_s", "fit_duration_median_s",  # evaluation.json
    "graph_time_s", "search_time_s", "total_time_s",  # reach.json, reach.npz
    "kernel_compile_s", "map_preparation_s",  # route.json, reach.json
    "coarse_time_s", "fine_time_s",  # route.json of plan --coarse-factor
    "planning_time_s",  # route.json, route.geojson, batch.json, batch.csv, mission.json
    "refresh_time_s", "update_wall_time_s", "wall_time_s",  # mission.json
    "update_wall",  # navigator.json (scalars): seconds, though its name does not say so
    "routes_per_s",  # batch.json: routes / elapsed_s
    "pricing_time_s", "solve_time_s", "improve_time_s",  # tour.json
    # the environment: {"terrawatt": ..., "numpy": ..., "python": ...} in a model file's model.json
    "versions",
})

#: An output (or archive member) larger than this, in bytes after masking, is compared by its digest
#: (``<name>.digest.json``: size, SHA-256, an array's dtype, shape and range, a text's first and last lines)
#: instead of a full golden copy, as are those a case names in ``golden_cases.DIGESTED``: the copies stay small.
DIGEST_OVER_BYTES = 100_000

_KEYS = "|".join(sorted(MASKED_KEYS))
# a masked key's value in JSON text: a number, a string, a literal, or an object without nested objects
_JSON_VALUE = re.compile(
    rf'("(?:{_KEYS})":\s*)(-?\d[\d.eE+-]*|-?Infinity|NaN|null|true|false|"(?:[^"\\]|\\.)*"|\{{[^{{}}]*\}})'
)


#: The same fields where the commands print them (``<case>/stdout.txt``): wall-clock timings, and the rates
#: derived from one, in the words that introduce them. Each pattern's groups are replaced by :data:`MASK`;
#: nothing else of the printout is.
MASKED_PRINTED = tuple(re.compile(p, re.MULTILINE) for p in (
    r"map preparation +(\d+\.\d+) s",  # plan, reach
    r"^(?:lattice moves|search|total) +(\d+\.\d+) s$",  # reach: graph_time_s, search_time_s, total_time_s
    r"coarse route (\d+\.\d+) s, corridor search (\d+\.\d+) s",  # plan --coarse-factor
    r"(\d+\.\d+) s on \d+ worker",  # batch, mission --monte-carlo, evaluate: elapsed_s
    r"(\d+\.\d+) routes/s",  # batch: routes_per_s
    r"loop computing (\d+\.\d+) s",  # mission: computing_time_s
    r"replayed in (\d+\.\d+) s \((\d+)x real time\)",  # replay: wall_time_s and the ratio to it
    r"pricing (\d+\.\d+) s .*solving (\d+\.\d+) s",  # tour: pricing_time_s, solve_time_s
    r"swapped in, in (\d+\.\d+) s$",  # tour: improve_time_s
    r"in (\d+\.\d+) s; wrote",  # train: fit_duration_s
))

#: Printed tables whose last column is a wall-clock timing, by that column's title (plan: planning_time_s).
MASKED_PRINTED_COLUMNS = ("plan s",)


def regenerating() -> bool:
    """True when ``TERRAWATT_REGEN_GOLDEN=1``: write the golden copies instead of comparing."""
    return os.environ.get(REGEN_ENV, "") == "1"


def mask_json_text(text: str) -> str:
    """``text`` with the value of every :data:`MASKED_KEYS` key replaced by ``"<masked>"``."""
    masked = _JSON_VALUE.sub(lambda m: f'{m.group(1)}"{MASK}"', text)
    json.loads(masked)  # still JSON: a value the pattern could not span would show here
    return masked


def mask_printed_text(text: str) -> str:
    """A command's printout ``text`` with every :data:`MASKED_PRINTED` group, and the last cell of each row of a
    table headed by a :data:`MASKED_PRINTED_COLUMNS` title (down to its first empty line), replaced by ``<masked>``."""
    for pattern in MASKED_PRINTED:
        text = pattern.sub(_mask_groups, text)
    lines, in_table = text.split("\n"), False
    for i, line in enumerate(lines):
        if line.rstrip().endswith(MASKED_PRINTED_COLUMNS):
            in_table = True
        elif not line.strip():
            in_table = False
        elif in_table and not set(line.strip()) <= {"-", "|", ":"}:
            head, _, _ = line.rstrip().rpartition(" ")
            lines[i] = f"{head} {MASK}"
    return "\n".join(lines)


def _mask_groups(match: re.Match) -> str:
    """``match``'s text with each of its groups replaced by :data:`MASK`."""
    text, start = match.group(0), match.start()
    for g in range(match.re.groups, 0, -1):  # from the last, so earlier offsets stand
        a, b = match.span(g)
        text = text[: a - start] + MASK + text[b - start:]
    return text


def mask_csv_text(text: str) -> str:
    """``text`` with the cells of every :data:`MASKED_KEYS` column replaced by ``<masked>``."""
    rows = list(csv.reader(io.StringIO(text, newline="")))
    if not rows or not MASKED_KEYS.intersection(rows[0]):
        return text
    columns = [j for j, name in enumerate(rows[0]) if name in MASKED_KEYS]
    for row in rows[1:]:
        for j in columns:
            if j < len(row) and row[j] != "":
                row[j] = MASK
    out = io.StringIO(newline="")
    terminator = "\r\n" if "\r\n" in text else "\n"
    csv.writer(out, lineterminator=terminator).writerows(rows)
    if not text.endswith(terminator):
        return out.getvalue().removesuffix(terminator)
    return out.getvalue()


def _digest(key: str, data: bytes) -> bytes:
    """A large output's stand-in: its size and SHA-256, and what a reader needs to see a change: an array's
    dtype, shape and range, a text's first and last lines."""
    doc: dict = {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}
    if key.endswith(".npy"):
        arr = np.load(io.BytesIO(data), allow_pickle=False)
        doc |= {"dtype": str(arr.dtype), "shape": list(arr.shape)}
        if arr.size and (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
            finite = arr[np.isfinite(arr)] if np.issubdtype(arr.dtype, np.floating) else arr
            doc |= {"finite": int(finite.size), "first": arr.ravel()[:4].tolist()}
            if finite.size:
                doc |= {"min": finite.min().item(), "max": finite.max().item()}
    else:
        lines = data.decode("utf-8", "replace").splitlines()
        doc |= {"lines": len(lines), "head": lines[:6], "tail": lines[-3:]}
    return (json.dumps(doc, indent=1) + "\n").encode()


def _stored(key: str, data: bytes, digested: tuple[str, ...]) -> dict[str, bytes]:
    """``{key: data}``, or ``{key + ".digest.json": digest}`` for a large or ``digested`` member."""
    if len(data) > DIGEST_OVER_BYTES or any(fnmatch.fnmatchcase(key, pattern) for pattern in digested):
        return {f"{key}.digest.json": _digest(key, data)}
    return {key: data}


def _plain(value):
    """A deserialised ROS message as JSON values: dataclass fields in order, arrays as lists, a JSON string parsed."""
    if dataclasses.is_dataclass(value):
        return {"__msgtype__": getattr(value, "__msgtype__", type(value).__name__)} | {
            f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, str) and value.startswith("{"):
        try:
            return json.loads(value)
        except ValueError:
            return value
    return value


def _bag_messages(path: Path) -> bytes:
    """A ROS 2 bag (``.mcap``) as JSON text: each topic's type and its messages with their log times (ns)."""
    from planner.ros_export import read_bag_topics

    topics = read_bag_topics(path, "/")
    doc = {f"/{topic}": {"type": msgtype, "messages": [{"log_time_ns": t, "message": _plain(m)} for t, m in messages]}
           for topic, (msgtype, messages) in sorted(topics.items())}
    return mask_json_text(json.dumps(doc, indent=1) + "\n").encode()


def _pixels(data: bytes) -> dict:
    import matplotlib.image

    rgba = np.ascontiguousarray(matplotlib.image.imread(io.BytesIO(data), format="png"))
    return {"shape": list(rgba.shape), "dtype": str(rgba.dtype), "sha256": hashlib.sha256(rgba.tobytes()).hexdigest()}


def _text_member(name: str, data: bytes) -> bytes:
    if name.endswith((".json", ".geojson")):
        return mask_json_text(data.decode("utf-8")).encode("utf-8")
    if name.endswith(".csv"):
        return mask_csv_text(data.decode("utf-8")).encode("utf-8")
    if name == "stdout.txt":
        return mask_printed_text(data.decode("utf-8")).encode("utf-8")
    return data


def members(files: dict[str, Path], digested: tuple[str, ...] = ()) -> dict[str, bytes]:
    """The compared members of a case's outputs ``{"<case>/<name>": path}`` (a path may be a folder), keyed by
    golden path; members matching a ``digested`` pattern (``fnmatch``) are compared by their digest."""
    out: dict[str, bytes] = {}
    figures: dict[str, dict[str, dict]] = {}
    expanded = {}
    for key, path in files.items():  # a folder stands for the files in it
        found = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
        expanded |= {key + p.as_posix().removeprefix(path.as_posix()): p for p in found}
    for key, path in sorted(expanded.items()):
        data = path.read_bytes()
        case, name = key.split("/", 1)
        if name.endswith(".png"):
            figures.setdefault(case, {})[name] = _pixels(data)
        elif name.endswith(".mcap"):  # compared as the messages it holds: a timing sits in a message's JSON text
            out.update(_stored(f"{key}.messages.json", _bag_messages(path), digested))
        elif name.endswith((".zip", ".npz")) or data[:4] == b"PK\x03\x04":  # a registry's model files have no suffix
            with zipfile.ZipFile(io.BytesIO(data)) as archive:
                for member in sorted(archive.namelist()):
                    content = archive.read(member)
                    if member.endswith(".npy") and Path(member).stem in MASKED_KEYS:
                        content = MASK.encode()
                    # a member's name as a portable file name ("layer:ground.npy" -> "layer%3Aground.npy")
                    out.update(_stored(f"{key}/{quote(member, safe='/')}", _text_member(member, content), digested))
        else:
            out.update(_stored(key, _text_member(name, data), digested))
    for case, table in figures.items():
        out[f"{case}/figures.json"] = (json.dumps(table, indent=1, sort_keys=True) + "\n").encode()
    return out


def write_case(case: str, produced: dict[str, bytes]) -> None:
    """Replace the golden copies of ``case`` by ``produced`` (stale files of the case removed)."""
    shutil.rmtree(GOLDEN / case, ignore_errors=True)
    for key, data in produced.items():
        target = GOLDEN / key
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)


def _json_paths(a, b, path: str = "$") -> list[str]:
    """The first key paths at which two parsed JSON values differ."""
    if isinstance(a, dict) and isinstance(b, dict):
        found = [f"{path}.{k}: {'missing' if k not in a else 'present'} in golden, "
                 f"{'missing' if k not in b else 'present'} in output" for k in sorted(set(a) ^ set(b))]
        for k in a:
            if k in b:
                found += _json_paths(a[k], b[k], f"{path}.{k}")
        return found
    if isinstance(a, list) and isinstance(b, list):
        found = [] if len(a) == len(b) else [f"{path}: length {len(a)} in golden, {len(b)} in output"]
        for i, (x, y) in enumerate(zip(a, b)):
            found += _json_paths(x, y, f"{path}[{i}]")
        return found
    return [] if a == b and type(a) is type(b) else [f"{path}: golden {a!r:.80}, output {b!r:.80}"]


def _describe(key: str, golden: bytes, output: bytes) -> str:
    """A readable account of how ``output`` differs from ``golden``: first differing keys, lines or values."""
    lines = [f"--- {key} differs from its golden copy"]
    if key.endswith(".npy"):
        try:
            a, b = (np.load(io.BytesIO(x), allow_pickle=False) for x in (golden, output))
        except ValueError:
            return f"{lines[0]}: {golden[:40]!r} vs {output[:40]!r}"
        if a.shape != b.shape or a.dtype != b.dtype:
            return f"{lines[0]}: golden {a.dtype} {a.shape}, output {b.dtype} {b.shape}"
        bad = np.argwhere(~((a == b) | ((a != a) & (b != b))))
        first = tuple(int(i) for i in bad[0])
        extra = ""
        if np.issubdtype(a.dtype, np.number) and a.size:
            with np.errstate(invalid="ignore"):  # inf - inf where both are unreachable
                extra = f", largest difference {np.nanmax(np.abs(a.astype(float) - b.astype(float))):.6g}"
        return (f"{lines[0]}: {len(bad)} of {a.size} values differ, first at {first}: golden "
                f"{a[first].tolist()!r}, output {b[first].tolist()!r}{extra}")
    try:
        text_a, text_b = golden.decode("utf-8"), output.decode("utf-8")
    except UnicodeDecodeError:  # a binary file (GeoTIFF, PGM): where the bytes part
        first = next((i for i, (x, y) in enumerate(zip(golden, output)) if x != y), min(len(golden), len(output)))
        return f"{lines[0]}: binary, {len(golden)} bytes golden, {len(output)} output, first difference at byte {first}"
    if key.endswith((".json", ".geojson")):
        try:
            paths = _json_paths(json.loads(text_a), json.loads(text_b))
        except ValueError:
            paths = []
        if paths:
            lines.append(f"first differing keys ({len(paths)} in all):")
            lines += [f"  {p}" for p in paths[:12]]
        elif text_a != text_b:
            lines.append("same values, different text (formatting, key order or float text):")
    diff = list(difflib.unified_diff(text_a.splitlines(), text_b.splitlines(), "golden", "output", n=1, lineterm=""))
    lines += diff[:40] + ([f"... ({len(diff) - 40} more diff lines)"] if len(diff) > 40 else [])
    return "\n".join(lines)


def check_case(case: str, produced: dict[str, bytes]) -> None:
    """Compare ``produced`` with the golden copies of ``case``; raise AssertionError with a readable diff."""
    __tracebackhide__ = True  # pytest: show the diff, not this function
    root = GOLDEN / case
    if not root.is_dir():
        raise AssertionError(f"no golden copies for case {case!r} under {GOLDEN.name}/: "
                             f"regenerate with {REGEN_ENV}=1 (or python tests/golden/regenerate.py {case})")
    golden = {f"{case}/{p.relative_to(root).as_posix()}": p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}
    problems = [f"--- {k}: golden copy has no output (file no longer written?)" for k in sorted(set(golden) - set(produced))]
    problems += [f"--- {k}: new output without a golden copy" for k in sorted(set(produced) - set(golden))]
    problems += [_describe(k, golden[k], produced[k]) for k in sorted(set(golden) & set(produced)) if golden[k] != produced[k]]
    if problems:
        raise AssertionError(
            f"case {case!r}: {len(problems)} output(s) differ from the golden copies; if the change is deliberate, "
            f"regenerate with {REGEN_ENV}=1 (or python tests/golden/regenerate.py {case}) and commit the diff\n"
            + "\n".join(problems)
        )
