"""Comparing a rerun with its original results folder (compare/sdcompare-rerun).

Owns the answer to "did this rerun give back the same numbers?": every HDF5 dataset of the
rerun's field files (fields.h5, verification.h5: whichever it has; with --references also the
references' dolfinx/ and freefem/fields.h5 it has) against the same-named dataset of the
original's, bit for bit by default or within --rtol, and the numbers of each rerun case in
summary.json (matched to the original's case by level, u space, multiplier, p mass, p space and
δ; timings and file names are not compared). A rerun of one level / u space / multiplier holds a
subset of the original's datasets and cases: that is the normal case. Exit codes: 0 the same,
1 something differs (the first differing dataset and case are named), 2 bad input (one line on
stderr). See compare/README.md, "Rerun commands".

An elastic results folder (docs/elasticity.md: summary.json's "problem" is "elasticity"): its
solver cases (issue 46) as a scalar folder's — each rerun case's numbers against the original's
case of the same key (level, multiplier, δ, problem), every fields.h5 dataset —, and with
--references what its references solved (a folder without solver cases has nothing else: without
--references exit 2). Every file the rerun has under mesh/ (the
export the references read, sdcrack's one output there) and under dolfinx/ and freefem/: each
fields.h5 dataset as above, each reference summary.json case (by level; timings not compared),
the text outputs (u_level{L}.txt, crack_level{L}.txt, the XDMF files, mesh/level{L}/*.txt) byte
for byte (within --rtol word for word: an integer equal, another number within rtol of the
largest magnitude of its column in the original's file), the JSON files value by value (mesh/
scene.json's `levels`, the levels the run wrote, not compared); and report/report.json's values
(the errors, rates, SIFs, agreement and verdict the compare tool computed from them; not its
folder path and provenance; within --rtol not its strings that hold digits, sentences that print
rounded numbers) when the rerun has one. It prints "identical: N datasets, M text files, K
reference cases, J report.json values".
"""
import argparse
import math
import os
import re
import sys

import numpy as np

from . import cases, read
from .elastic_read import PROBLEM as ELASTIC
from .read import REFERENCE_TOOLS
from .render import fmt_delta

PROG = "sdcompare-rerun"
SAME, DIFFERENT, BAD_INPUT = 0, 1, 2
FIELD_FILES = ("fields.h5", "verification.h5")  # sdcrack's: a rerun has one at least
REFERENCE_FIELDS = tuple(f"{tool}/fields.h5" for tool in REFERENCE_TOOLS)
# wall-clock times and the names of the case's XDMF files: not results
NOT_COMPARED = ("timings_s", "fields_series", "fields_state")
DEFAULT_KKT_TOLERANCE = 1e-10


class BadInput(Exception):
    """Missing, unreadable or mismatched input (exit 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise BadInput(message)


def parse_args(argv):
    p = _Parser(prog=PROG, description="Compares a rerun (the output of a report's or tools/cases' "
                "rerun command) with the results folder it reruns: every dataset of the rerun's "
                "fields.h5 / verification.h5 and the numbers of each rerun case in summary.json. "
                "Exit 0 the same, 1 different, 2 bad input.")
    p.add_argument("original", help="the results folder the command came from, OUT/<scene>/")
    p.add_argument("rerun", help="the rerun: the command's --out folder (sdcrack-rerun/<name>) "
                   "or the results folder inside it")
    p.add_argument("--rtol", type=_rtol, default=None, metavar="X",
                   help="accept a float dataset whose largest difference is at most X times the "
                   "original dataset's largest magnitude, and summary.json floats within X "
                   "relative (KKT residuals: both at most summary.json's kkt_tolerance); "
                   "default: bit for bit")
    p.add_argument("--references", action="store_true",
                   help="also compare the references' dolfinx/ and freefem/fields.h5 that the "
                   "rerun has (written by this checkout's reference scripts, not by the recorded "
                   "binary: they differ where those scripts changed since the original)")
    return p.parse_args(argv)


def _rtol(text):
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}")
    if not (math.isfinite(x) and x >= 0):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0: {text!r}")
    return x


# ---------------------------------------------------------------- the two folders
def results_folder(path):
    """The results folder `path` names: itself when it holds summary.json, else the one folder
    inside it that does (a rerun command's --out holds OUT/<scene>/)."""
    if not os.path.isdir(path):
        raise BadInput(f"{path}: " + ("not a folder" if os.path.exists(path) else "no such folder"))
    if os.path.isfile(os.path.join(path, "summary.json")):
        return path
    try:
        entries = os.listdir(path)
    except OSError as exc:
        raise BadInput(f"{path}: unreadable folder ({exc.strerror})")
    inner = sorted(e for e in entries if os.path.isfile(os.path.join(path, e, "summary.json")))
    if len(inner) == 1:
        return os.path.join(path, inner[0])
    if inner:
        raise BadInput(f"{path}: holds several results folders ({', '.join(inner)}): name one")
    raise BadInput(f"{path}: not a results folder (no summary.json in it or in a folder inside)")


def load_summary(folder):
    """folder/summary.json (read.load_json), which must hold a `cases` list; BadInput otherwise."""
    path = os.path.join(folder, "summary.json")
    try:
        summary = read.load_json(path)
    except read.InputError as exc:
        raise BadInput(str(exc))
    if not isinstance(summary, dict) or not isinstance(summary.get("cases"), list):
        raise BadInput(f"{path}: no `cases` list: not an sdcrack summary.json")
    return summary


# ---------------------------------------------------------------- summary.json cases
def case_key(c):
    """A case's identity (cases.CaseKey), or None for an entry that lacks one."""
    try:
        return cases.case_key(c)
    except (KeyError, TypeError, ValueError):
        return None


def case_label(k):
    return (f"level {k.level} {k.u_space} {k.multiplier} {k.p_mass} {k.p_space} "
            f"δ {fmt_delta(k.delta)}")


def cases_by_key(summary, folder):
    out = {}
    for c in summary["cases"]:
        key = case_key(c) if isinstance(c, dict) else None
        if key is None:
            raise BadInput(f"{folder}/summary.json: a case without level, u_space, multiplier "
                           "or delta")
        out[key] = c
    return out


def flatten(value, prefix=""):
    """{dotted name: leaf value} of a case entry, NOT_COMPARED left out."""
    if not isinstance(value, dict):
        return {prefix: value}
    out = {}
    for k, v in value.items():
        if not prefix and k in NOT_COMPARED:
            continue
        out.update(flatten(v, f"{prefix}.{k}" if prefix else str(k)))
    return out


def _number(v):
    return isinstance(v, float) or (isinstance(v, int) and not isinstance(v, bool))


def value_agrees(name, a, b, rtol, leaves, kkt_tolerance):
    """Whether the rerun's value `a` of a case's `name` agrees with the original's `b`: equal
    (JSON values) by default; with rtol, floats within rtol relative, KKT residuals both at most
    kkt_tolerance (their digits are round-off), a quadrature estimate within rtol of its error."""
    if a == b and type(a) is type(b):
        return True
    if rtol is None or not (isinstance(a, float) or isinstance(b, float)):
        return False
    if not (_number(a) and _number(b)):
        return False
    diff = abs(a - b)
    if diff <= rtol * max(abs(a), abs(b)):
        return True
    if name.startswith("kkt."):
        return max(abs(a), abs(b)) <= kkt_tolerance
    if name.startswith("errors_quadrature."):
        error = leaves.get("errors." + name.split(".", 1)[1])
        return _number(error) and diff <= rtol * abs(error)
    return False


def case_difference(rerun_case, original_case, rtol, kkt_tolerance):
    """None, or "NAME: RERUN vs original ORIGINAL" for the first differing number of a case."""
    a, b = flatten(rerun_case), flatten(original_case)
    for name in sorted(set(a) | set(b)):
        if name not in b:
            return f"{name}: {a[name]!r}, absent in the original"
        if name not in a:
            return f"{name}: absent, {b[name]!r} in the original"
        if not value_agrees(name, a[name], b[name], rtol, a, kkt_tolerance):
            return f"{name}: {a[name]!r} vs original {b[name]!r}"
    return None


def check_same_scene(rerun_sum, original_sum, rerun_dir, original_dir):
    if rerun_sum.get("scene") != original_sum.get("scene"):
        raise BadInput(f"{rerun_dir} reruns scene {rerun_sum.get('scene')!r}, {original_dir} is "
                       f"scene {original_sum.get('scene')!r}")


def kkt_tolerance(original_sum):
    tol = original_sum.get("kkt_tolerance")
    return tol if _number(tol) else DEFAULT_KKT_TOLERANCE


def compare_cases(rerun_sum, original_sum, rerun_dir, original_dir, rtol):
    """([(case label, difference)] in the rerun's order, number of cases compared)."""
    check_same_scene(rerun_sum, original_sum, rerun_dir, original_dir)
    original = cases_by_key(original_sum, original_dir)
    rerun = cases_by_key(rerun_sum, rerun_dir)
    if not rerun:
        raise BadInput(f"{rerun_dir}/summary.json: no cases")
    tol = kkt_tolerance(original_sum)
    diffs = []
    for key, c in rerun.items():
        if key not in original:
            raise BadInput(f"{rerun_dir}: case {case_label(key)} is not in "
                           f"{original_dir}/summary.json: not a rerun of that folder")
        why = case_difference(c, original[key], rtol, tol)
        if why:
            diffs.append((case_label(key), why))
    return diffs, len(rerun)


# ---------------------------------------------------------------- the field files
def field_files(rerun_dir, original_dir, references=False):
    """The field files to compare: those of FIELD_FILES (and REFERENCE_FIELDS with `references`)
    that the rerun has."""
    names = [n for n in FIELD_FILES if os.path.isfile(os.path.join(rerun_dir, n))]
    if not names:
        raise BadInput(f"{rerun_dir}: no {' or '.join(FIELD_FILES)} to compare")
    if references:
        names += [n for n in REFERENCE_FIELDS if os.path.isfile(os.path.join(rerun_dir, n))]
    for n in names:
        if not os.path.isfile(os.path.join(original_dir, n)):
            raise BadInput(f"{original_dir}: no {n}, which the rerun has")
    return names


def _open(h5py, path):
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        raise BadInput(f"{path}: unreadable HDF5 file ({exc})")


def dataset_names(h5py, f):
    names = []
    f.visititems(lambda name, obj: names.append(name) if isinstance(obj, h5py.Dataset) else None)
    return sorted(names)


def _read(f, name, path):
    try:
        return np.asarray(f[name][()])
    except (OSError, KeyError, TypeError, ValueError) as exc:
        raise BadInput(f"{path}: dataset /{name} unreadable ({exc})")


def max_differences(a, b):
    """(largest |a − b|, that over the largest |b|) of two same-shape numeric arrays; NaN against
    NaN is no difference, NaN against a number an infinite one."""
    a, b = a.astype(np.float64), b.astype(np.float64)
    with np.errstate(invalid="ignore", over="ignore"):
        d = np.abs(a - b)
    d[(a == b) | (np.isnan(a) & np.isnan(b))] = 0.0
    d[np.isnan(d)] = np.inf
    dmax = float(d.max()) if d.size else 0.0
    finite = np.abs(b[np.isfinite(b)])
    scale = float(finite.max()) if finite.size else 0.0
    rel = dmax / scale if scale > 0 else (0.0 if dmax == 0 else math.inf)
    return dmax, rel


def dataset_difference(a, b, rtol):
    """None when the rerun's dataset `a` matches the original's `b` (bit for bit, or a float
    dataset within rtol), else what differs."""
    if a.shape != b.shape:
        return f"shape {a.shape} vs original {b.shape}"
    if a.dtype != b.dtype:
        return f"dtype {a.dtype} vs original {b.dtype}"
    if a.tobytes() == b.tobytes():
        return None
    if a.dtype.kind not in "fiub":
        return f"values differ ({a.dtype} data)"
    dmax, rel = max_differences(a, b)
    if rtol is not None and a.dtype.kind == "f" and rel <= rtol:
        return None
    if dmax == 0:
        return "equal values, different bits (a signed zero or a NaN payload)"
    return f"max abs difference {dmax:.2e}, max rel difference {rel:.2e}"


def compare_fields(h5py, rerun_dir, original_dir, rtol, references=False):
    """([(dataset label, difference)] in file and name order, number of datasets compared)."""
    diffs, count = [], 0
    for name in field_files(rerun_dir, original_dir, references):
        rpath, opath = os.path.join(rerun_dir, name), os.path.join(original_dir, name)
        with _open(h5py, rpath) as rf, _open(h5py, opath) as of:
            try:
                file_diffs = compare_file(h5py, rf, of, rpath, opath, rtol)
            except (OSError, RuntimeError, KeyError) as exc:  # a damaged file's internals
                raise BadInput(f"{rpath} or {opath}: unreadable HDF5 content ({exc})")
        count += len(file_diffs)
        diffs += [(f"/{ds} ({name})", why) for ds, why in file_diffs if why]
    return diffs, count


def compare_file(h5py, rf, of, rpath, opath, rtol):
    """[(dataset name, difference or None)] of every dataset of the rerun's open file `rf`."""
    out = []
    for ds in dataset_names(h5py, rf):
        if not isinstance(of.get(ds), h5py.Dataset):
            raise BadInput(f"{rpath}: dataset /{ds} is not in {opath} (not a rerun of that "
                           "folder, or by a binary that writes other datasets)")
        out.append((ds, dataset_difference(_read(rf, ds, rpath), _read(of, ds, opath), rtol)))
    return out


# ---------------------------------------------------------------- an elastic folder (no cases)
MESH_EXPORT = "mesh"  # the export the references read (docs/elasticity.md): sdcrack's output
REPORT_JSON = os.path.join("report", "report.json")
# top-level keys of JSON files that are not results: the levels a run wrote (a rerun of one
# level writes [L]); the report's folder path and provenance (dates, command lines, paths, cores)
JSON_NOT_COMPARED = {os.path.join(MESH_EXPORT, "scene.json"): ("levels",),
                     REPORT_JSON: ("results_dir", "provenance")}
INTEGER = re.compile(r"[+-]?[0-9]+")
DIGIT = re.compile(r"[0-9]")


def is_elastic(summary):
    return summary.get("problem") == ELASTIC


def elastic_tools(rerun_dir, original_dir):
    """The reference tools whose outputs the rerun has (each one the original has too)."""
    tools = [t for t in REFERENCE_TOOLS if os.path.isdir(os.path.join(rerun_dir, t))]
    if not tools:
        folders = ", ".join(t + "/" for t in REFERENCE_TOOLS)
        raise BadInput(f"{rerun_dir}: no reference outputs ({folders}) to compare")
    for t in tools:
        if not os.path.isdir(os.path.join(original_dir, t)):
            raise BadInput(f"{original_dir}: no {t}/, which the rerun has")
    return tools


def elastic_files(rerun_dir, original_dir, tools):
    """Every file of the rerun under mesh/ and its tools' folders, relative to rerun_dir (in
    folder and name order); each must be in the original."""
    names = []
    for top in (MESH_EXPORT, *tools):
        for dirpath, dirnames, filenames in os.walk(os.path.join(rerun_dir, top)):
            dirnames.sort()
            names += [os.path.relpath(os.path.join(dirpath, f), rerun_dir)
                      for f in sorted(filenames)]
    for n in names:
        if not os.path.isfile(os.path.join(original_dir, n)):
            raise BadInput(f"{original_dir}: no {n}, which the rerun has")
    return names


def _read_bytes(path):
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise BadInput(f"{path}: unreadable ({exc.strerror})")


def _decode(data, path):
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise BadInput(f"{path}: not a UTF-8 text file")


def column_scales(rows):
    """{column: largest |number| in that column of the original's rows}."""
    scales = {}
    for row in rows:
        for j, word in enumerate(row):
            try:
                x = abs(float(word))
            except ValueError:
                continue
            if math.isfinite(x):
                scales[j] = max(scales.get(j, 0.0), x)
    return scales


def words_agree(a, b, rtol, scale):
    """Whether the rerun's word `a` agrees within rtol with the original's different word `b`:
    both numbers, not both integers (an index or a flag must be equal, tolerance or not), at most
    rtol × the largest magnitude of the original's column apart."""
    if rtol is None or (INTEGER.fullmatch(a) and INTEGER.fullmatch(b)):
        return False
    try:
        x, y = float(a), float(b)
    except ValueError:
        return False
    return scale is not None and abs(x - y) <= rtol * scale


def text_difference(a, b, rtol):
    """None when the rerun's text `a` matches the original's `b` (byte for byte; with rtol word
    for word, numbers by words_agree), else where it first differs."""
    if a == b:
        return None
    ra, rb = [line.split() for line in a.splitlines()], [line.split() for line in b.splitlines()]
    if len(ra) != len(rb):
        return f"{len(ra)} lines vs original {len(rb)}"
    scales = column_scales(rb) if rtol is not None else {}
    for i, (x, y) in enumerate(zip(ra, rb), start=1):
        if len(x) != len(y):
            return f"line {i}: {len(x)} words vs original {len(y)}"
        for j, (s, t) in enumerate(zip(x, y)):
            if s != t and not words_agree(s, t, rtol, scales.get(j)):
                return f"line {i} word {j + 1}: {s} vs original {t}"
    return None if rtol is not None else "the same words, other bytes (spaces or line ends)"


def json_leaves(value, prefix=""):
    """{path: leaf} of a JSON value, through objects ("a.b") and arrays ("a[3]")."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            out.update(json_leaves(v, f"{prefix}.{k}" if prefix else str(k)))
        return out
    if isinstance(value, list):
        out = {}
        for i, v in enumerate(value):
            out.update(json_leaves(v, f"{prefix}[{i}]"))
        return out
    return {prefix: value}


def json_values(path, name):
    """The leaves of the JSON file `path` (relative name `name`), JSON_NOT_COMPARED left out."""
    try:
        doc = read.load_json(path)
    except read.InputError as exc:
        raise BadInput(str(exc))
    if isinstance(doc, dict):
        doc = {k: v for k, v in doc.items() if k not in JSON_NOT_COMPARED.get(name, ())}
    return json_leaves(doc)


def json_differences(a, b, rtol):
    """[(leaf, difference)] of the rerun's leaves `a` against the original's `b`, in name order:
    values equal (value_agrees: floats within rtol); with rtol a string that holds a digit (a
    sentence printing rounded numbers) is not compared."""
    out = []
    for name in sorted(set(a) | set(b)):
        if name not in b:
            out.append((name, f"{a[name]!r}, absent in the original"))
        elif name not in a:
            out.append((name, f"absent, {b[name]!r} in the original"))
        elif rtol is not None and all(isinstance(v, str) and DIGIT.search(v)
                                      for v in (a[name], b[name])):
            continue
        elif not value_agrees(name, a[name], b[name], rtol, a, DEFAULT_KKT_TOLERANCE):
            out.append((name, f"{a[name]!r} vs original {b[name]!r}"))
    return out


def file_difference(rpath, opath, name, rtol):
    """None, or what differs between the rerun's text or JSON file and the original's."""
    a, b = _read_bytes(rpath), _read_bytes(opath)
    if a == b:
        return None
    if name.endswith(".json"):
        diffs = json_differences(json_values(rpath, name), json_values(opath, name), rtol)
        if diffs:
            return f"{diffs[0][0]}: {diffs[0][1]}"
        return None if rtol is not None or name in JSON_NOT_COMPARED else \
            "the same values, other bytes"
    return text_difference(_decode(a, rpath), _decode(b, opath), rtol)


def load_reference_cases(folder, tool):
    path = os.path.join(folder, tool, "summary.json")
    try:
        doc = read.load_json(path)
    except read.InputError as exc:
        raise BadInput(str(exc))
    if not isinstance(doc, dict) or not isinstance(doc.get("cases"), list):
        raise BadInput(f"{path}: no `cases` list: not a reference summary.json")
    out = {}
    for c in doc["cases"]:
        level = c.get("level") if isinstance(c, dict) else None
        if not isinstance(level, int) or isinstance(level, bool) or level in out:
            raise BadInput(f"{path}: a case without an integer level of its own")
        out[level] = c
    return out


def compare_reference_cases(rerun_dir, original_dir, tool, rtol, tol):
    """([(label, difference)], number of cases compared) of the tool's summary.json cases, each
    rerun case against the original's of its level (timings not compared)."""
    original, rerun = (load_reference_cases(d, tool) for d in (original_dir, rerun_dir))
    diffs = []
    for level, c in rerun.items():
        if level not in original:
            raise BadInput(f"{rerun_dir}/{tool}: level {level} is not in "
                           f"{original_dir}/{tool}/summary.json: not a rerun of that folder")
        why = case_difference(c, original[level], rtol, tol)
        if why:
            diffs.append((f"{tool}/summary.json case level {level}", why))
    return diffs, len(rerun)


def compare_elastic_outputs(h5py, rerun_dir, original_dir, tools, rtol, tol):
    """{kind: ([(label, difference)], number compared)} for the kinds datasets, text files
    (mesh/ and the tools' text and JSON files) and reference cases."""
    out = {"datasets": ([], 0), "text files": ([], 0), "reference cases": ([], 0)}

    def add(kind, diffs, n):
        out[kind] = (out[kind][0] + diffs, out[kind][1] + n)

    for name in elastic_files(rerun_dir, original_dir, tools):
        rpath, opath = os.path.join(rerun_dir, name), os.path.join(original_dir, name)
        if name.endswith(".h5"):
            with _open(h5py, rpath) as rf, _open(h5py, opath) as of:
                try:
                    file_diffs = compare_file(h5py, rf, of, rpath, opath, rtol)
                except (OSError, RuntimeError, KeyError) as exc:
                    raise BadInput(f"{rpath} or {opath}: unreadable HDF5 content ({exc})")
            add("datasets", [(f"/{ds} ({name})", why) for ds, why in file_diffs if why],
                len(file_diffs))
        elif os.path.dirname(name) in tools and os.path.basename(name) == "summary.json":
            add("reference cases", *compare_reference_cases(
                rerun_dir, original_dir, os.path.dirname(name), rtol, tol))
        else:
            why = file_difference(rpath, opath, name, rtol)
            add("text files", [(name, why)] if why else [], 1)
    return out


def compare_report(rerun_dir, original_dir, rtol):
    """([(leaf, difference)], number of values compared) of the rerun's report/report.json
    against the original's, or None when the rerun has none."""
    rpath, opath = os.path.join(rerun_dir, REPORT_JSON), os.path.join(original_dir, REPORT_JSON)
    if not os.path.isfile(rpath):
        return None
    if not os.path.isfile(opath):
        raise BadInput(f"{original_dir}: no {REPORT_JSON}, which the rerun has")
    a, b = json_values(rpath, REPORT_JSON), json_values(opath, REPORT_JSON)
    return json_differences(a, b, rtol), len(a)


def elastic_case_key(c):
    """An elastic solver case's identity (docs/elasticity.md: level, multiplier, δ, problem; no
    u space or p axes), or None for an entry that lacks one."""
    try:
        return (int(c["level"]), str(c["multiplier"]), float(c["delta"]), str(c["problem"]))
    except (KeyError, TypeError, ValueError):
        return None


def compare_elastic_cases(rerun_sum, original_sum, rerun_dir, original_dir, rtol):
    """([(case label, difference)], number compared) of the rerun's elastic solver cases against
    the original's of the same key (their numbers as a scalar case's: case_difference)."""
    by = []
    for folder, summary in ((rerun_dir, rerun_sum), (original_dir, original_sum)):
        out = {}
        for c in summary["cases"]:
            key = elastic_case_key(c) if isinstance(c, dict) else None
            if key is None:
                raise BadInput(f"{folder}/summary.json: an elastic case without level, "
                               "multiplier, delta or problem")
            out[key] = c
        by.append(out)
    rerun, original = by
    tol = kkt_tolerance(original_sum)
    diffs = []
    for key, c in rerun.items():
        label = f"level {key[0]} {key[1]} δ {fmt_delta(key[2])}"
        if key not in original:
            raise BadInput(f"{rerun_dir}: case {label} is not in {original_dir}/summary.json: "
                           "not a rerun of that folder")
        why = case_difference(c, original[key], rtol, tol)
        if why:
            diffs.append((label, why))
    return diffs, len(rerun)


def compare_elastic(h5py, rerun_dir, original_dir, rerun_sum, original_sum, rtol, references):
    """(lines, exit code) of an elastic folder's rerun: its solver cases (summary.json's numbers
    by key, fields.h5's datasets) as a scalar folder's, and with --references its references'
    outputs (and the report); BadInput when there is nothing to compare (no solver case and no
    --references), or for a folder that is not one of the same scene."""
    check_same_scene(rerun_sum, original_sum, rerun_dir, original_dir)
    for folder, summary in ((rerun_dir, rerun_sum), (original_dir, original_sum)):
        if not is_elastic(summary):
            raise BadInput(f"{folder}: a scalar results folder, the other one is elastic")
    solver = bool(rerun_sum["cases"])
    if not references and not solver:
        raise BadInput(f"{rerun_dir}: an elastic scene's folder, no solver cases to compare: "
                       "--references compares its references' outputs")
    kinds = {}
    if solver:
        kinds["cases"] = compare_elastic_cases(rerun_sum, original_sum, rerun_dir, original_dir,
                                               rtol)
        kinds["datasets"] = compare_fields(h5py, rerun_dir, original_dir, rtol)
    if not references:
        lines, code = report_kinds(kinds, rtol)
        said = references_line(rerun_dir, original_dir, references)
        return lines + ([said] if said else []), code
    tools = elastic_tools(rerun_dir, original_dir)
    for kind, (d, n) in compare_elastic_outputs(h5py, rerun_dir, original_dir, tools, rtol,
                                                kkt_tolerance(original_sum)).items():
        before = kinds.get(kind, ([], 0))
        kinds[kind] = (before[0] + d, before[1] + n)
    said = compare_report(rerun_dir, original_dir, rtol)
    if said is not None:
        kinds["report.json values"] = said
    lines, code = report_kinds(kinds, rtol)
    if said is None:
        lines.append(f"{REPORT_JSON}: not in the rerun, not compared")
    reused = [t for t in REFERENCE_TOOLS
              if os.path.isdir(os.path.join(original_dir, t)) and t not in tools]
    lines.append(f"references: {', '.join(tools)} rerun, compared"
                 + (f"; {', '.join(reused)} not in the rerun" if reused else ""))
    return lines, code


# the label of a difference of each kind in a "differs:" line
KIND_LABEL = {"cases": "summary.json case ", "datasets": "dataset ", "text files": "file ",
              "reference cases": "",
              "report.json values": f"{REPORT_JSON}: "}


def report_kinds(kinds, rtol):
    """The lines and exit code of an elastic comparison, {kind: (differences, count)}."""
    counts = [f"{n} {kind}" for kind, (_, n) in kinds.items()]
    if not any(d for d, _ in kinds.values()):
        what = "identical" if rtol is None else f"the same within rtol {rtol:g}"
        return [f"{what}: {', '.join(counts)}"], SAME
    lines = [f"differs: {KIND_LABEL[kind]}{d[0][0]}: {d[0][1]}"
             for kind, (d, _) in kinds.items() if d]
    parts = [f"{len(d)} of {n} {kind}" for kind, (d, n) in kinds.items()]
    lines.append(", ".join(parts[:-1]) + f" and {parts[-1]} differ"
                 + (" bit for bit" if rtol is None else f" beyond rtol {rtol:g}")
                 + " (the first of each is named above)")
    return lines, DIFFERENT


# ---------------------------------------------------------------- the verdict
def report(field_diffs, n_fields, case_diffs, n_cases, rtol):
    """The lines printed and the exit code."""
    if not field_diffs and not case_diffs:
        what = "identical" if rtol is None else f"the same within rtol {rtol:g}"
        return [f"{what}: {n_fields} datasets, {n_cases} cases"], SAME
    lines = []
    if field_diffs:
        label, why = field_diffs[0]
        lines.append(f"differs: dataset {label}: {why}")
    if case_diffs:
        label, why = case_diffs[0]
        lines.append(f"differs: summary.json case {label}: {why}")
    lines.append(f"{len(field_diffs)} of {n_fields} datasets and {len(case_diffs)} of {n_cases} "
                 "cases differ" + (" bit for bit" if rtol is None else f" beyond rtol {rtol:g}")
                 + " (the first of each is named above)")
    return lines, DIFFERENT


def references_line(rerun_dir, original_dir, references):
    """What the rerun did with the original's references (its REFERENCE_TOOLS folders), or None
    when it has none: which it reran (compared with --references, else not), and which it did not
    rerun (a rerun command's --solver-only) and so reuses from the original."""
    tools = [t for t in REFERENCE_TOOLS if os.path.isdir(os.path.join(original_dir, t))]
    if not tools:
        return None
    rerun = [t for t in tools if os.path.isdir(os.path.join(rerun_dir, t))]
    reused = [t for t in tools if t not in rerun]
    parts = []
    if rerun:
        parts.append(f"{', '.join(rerun)} rerun, "
                     + ("compared" if references else "not compared (--references compares them)"))
    if reused:
        parts.append(f"{', '.join(reused)} not rerun (--solver-only): the original's "
                     f"{', '.join(os.path.join(original_dir, t) for t in reused)} reused")
    return "references: " + "; ".join(parts)


def compare(original, rerun, rtol=None, references=False):
    """(lines, exit code) of comparing the rerun folder with the original; BadInput on bad input.
    The lines end with references_line when the original has references."""
    try:
        import h5py
    except ImportError as exc:
        raise BadInput(f"needs h5py ({exc})")
    original_dir, rerun_dir = results_folder(original), results_folder(rerun)
    if os.path.realpath(original_dir) == os.path.realpath(rerun_dir):
        raise BadInput(f"{original_dir}: the same folder twice")
    rerun_sum, original_sum = load_summary(rerun_dir), load_summary(original_dir)
    if is_elastic(rerun_sum) or is_elastic(original_sum):
        return compare_elastic(h5py, rerun_dir, original_dir, rerun_sum, original_sum, rtol,
                               references)
    case_diffs, n_cases = compare_cases(rerun_sum, original_sum, rerun_dir, original_dir, rtol)
    field_diffs, n_fields = compare_fields(h5py, rerun_dir, original_dir, rtol, references)
    lines, code = report(field_diffs, n_fields, case_diffs, n_cases, rtol)
    said = references_line(rerun_dir, original_dir, references)
    return lines + ([said] if said else []), code


def main(argv):
    try:
        args = parse_args(argv)
        lines, code = compare(args.original, args.rerun, args.rtol, args.references)
    except BadInput as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return BAD_INPUT
    print("\n".join(lines))
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
