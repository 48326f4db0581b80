"""Report rendering (Markdown + self-contained HTML + JSON) and the atomic report folder write.

A report is a list of sections: dict(title, paras=[str], tables=[(headers, rows) or (headers, rows,
caption)], images=[png], paras_after=[str], fold=bool). Tables of more than FOLD_ROWS rows are
folded in <details> (caption: what the table holds) unless the section says fold=False (the
summary). A cell that is None or a float that is not finite is written "–" (never "None", "nan").
Markdown and HTML walk the sections in one order (_walk); the HTML page's skeleton and stylesheet
are page.py's, shared with the campaign index.
"""
import base64
import html
import json
import math
import os
import shutil
import struct
import tempfile

from .page import cell_class, page, scroll_table
from sdshared.sdresults import replace_folder
from .cases import (DEFAULT_P_MASS, DEFAULT_P_SPACE, p_mass, p_space, p_space_tag,
                    shortest_exponent_form, variant_suffix)

# Tables longer than this are folded (<details>) outside the summary section.
FOLD_ROWS = 8
# Modes of the published report folder and its files, whatever the umask (mkdtemp gives 0700).
FOLDER_MODE = 0o755
FILE_MODE = 0o644


def fmt(v, spec=".3e"):
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "**NO**"
    if isinstance(v, float):
        return format(v, spec) if math.isfinite(v) else "–"
    return str(v)


def fmt_rate(v):
    return "–" if v is None or not math.isfinite(v) else f"{v:.2f}"


def fmt_delta(d):
    """δ as `1e-2`, `1e-10`, `2.5e-3`, `1` or `0` (never `0e0`, `1.0e-02`, `0.0`, `0.01`): the
    shortest digits that parse back to the same float64, so the text is also a valid command-line
    value (`--delta 1e-2`). None or not finite: "–"."""
    if d is None:
        return "–"
    d = float(d)
    if not math.isfinite(d):
        return "–"
    if d == 0:
        return "0"
    mant, e = shortest_exponent_form(abs(d))
    return ("-" if d < 0 else "") + (mant if e == 0 else f"{mant}e{e}")


def case_text(k):
    """"level L u m[ lumped][ ptangential] δ=D" of a case key (cases.CaseKey): how every check
    names a case."""
    return (f"level {k.level} {k.u_space} {k.multiplier}{variant_suffix(k.p_mass, k.p_space)} "
            f"δ={fmt_delta(k.delta)}")


def cell(c):
    """A table cell as text: None and non-finite floats are "–"."""
    if c is None:
        return "–"
    if isinstance(c, float) and not math.isfinite(c):
        return "–"
    return str(c)


def _table_parts(t):
    headers, rows = t[0], t[1]
    caption = t[2] if len(t) > 2 else None
    return headers, rows, caption


def _fold_summary(headers, rows, caption):
    what = caption or ("table: " + ", ".join(headers[:5]) + (", …" if len(headers) > 5 else ""))
    return f"{what} ({len(rows)} rows, click to open)"


def _folded(section, rows):
    """A section's `fold`: True (default) folds tables longer than FOLD_ROWS, "always" every
    table (provenance: long cells of command lines), False none."""
    fold = section.get("fold", True)
    return fold == "always" or (bool(fold) and len(rows) > FOLD_ROWS)


def _walk(sections, blocks):
    """The lines of the sections, in the report's order (a section's title, its paras, its lead
    images, its tables (the empty ones left out), its images, its paras after), each written by
    `blocks` (_MarkdownBlocks or _HtmlBlocks): one walk for both formats."""
    out = []
    for s in sections:
        out += blocks.heading(s["title"])
        for p in s.get("paras", []):
            out += blocks.para(p)
        for img in s.get("lead_images", []):
            out += blocks.image(img)
        for t in s.get("tables", []):
            headers, rows, caption = _table_parts(t)
            if rows:
                out += blocks.table(headers, rows, caption, _folded(s, rows))
        for img in s.get("images", []):
            out += blocks.image(img)
        for p in s.get("paras_after", []):
            out += blocks.para(p)
    return out


class _MarkdownBlocks:
    """report.md's blocks, each followed by an empty line; a folded table inside <details>."""

    @staticmethod
    def heading(title):
        return [f"## {title}", ""]

    @staticmethod
    def para(p):
        return [p, ""]

    @staticmethod
    def image(img):
        return [f"![{img}]({img})", ""]

    @staticmethod
    def table(headers, rows, caption, fold):
        out = []
        if fold:
            out += [f"<details><summary>{html.escape(_fold_summary(headers, rows, caption))}"
                    "</summary>", ""]
        elif caption:
            out += [f"*{caption}*", ""]
        out.append("| " + " | ".join(headers) + " |")
        out.append("|" + "---|" * len(headers))
        for r in rows:
            out.append("| " + " | ".join(cell(c) for c in r) + " |")
        out.append("")
        if fold:
            out += ["</details>", ""]
        return out


def markdown(title, sections):
    """report.md: the title, then the sections (_walk)."""
    return "\n".join([f"# {title}", ""] + _walk(sections, _MarkdownBlocks))


def _inline_md(text):
    t = html.escape(text)
    parts = t.split("**")
    t = "".join(f"<b>{p}</b>" if i % 2 else p for i, p in enumerate(parts))
    parts = t.split("`")
    return "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))


def _td(text):
    return f"<td class='{cell_class(text)}'>{_inline_md(text)}</td>"


# The PNG text chunk in which plots.py writes a plot's smallest text, in the PNG's pixels.
MIN_FONT_KEY = "min-font-px"


def _png_texts(data):
    """{keyword: text} of the tEXt chunks of a PNG's bytes."""
    out, pos = {}, 8
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        if kind == b"tEXt":
            key, _, value = data[pos + 8:pos + 8 + length].partition(b"\0")
            out[key.decode("latin-1")] = value.decode("latin-1")
        elif kind == b"IEND":
            break
        pos += 12 + length
    return out


def _img(folder, img):
    """An image inlined as base64, its id the file name's stem (rates-SCENE, delta-SCENE, …),
    inside a link to its file in the report folder (the full-size view). data-min-font-px: the
    smallest text of the PNG in its own pixels (its MIN_FONT_KEY chunk), which a reader of the page
    scales by the shown width to know the size the text is shown at."""
    with open(os.path.join(folder, img), "rb") as fh:
        data = fh.read()
    b64 = base64.b64encode(data).decode("ascii")
    ident, name = html.escape(os.path.splitext(img)[0]), html.escape(img)
    font = _png_texts(data).get(MIN_FONT_KEY)
    font_attr = f" data-min-font-px='{html.escape(font)}'" if font else ""
    return (f"<p class='plot'><a href='{name}' title='{name}: full size'><img id='{ident}' "
            f"alt='{name}'{font_attr} src='data:image/png;base64,{b64}'></a></p>")


class _HtmlBlocks:
    """index.html's blocks (page.py's conventions), one line each; the images inlined from
    `folder`; a folded table inside <details>."""

    def __init__(self, folder):
        self.folder = folder

    @staticmethod
    def heading(title):
        return [f"<h2>{html.escape(title)}</h2>"]

    @staticmethod
    def para(p):
        return [f"<p>{_inline_md(p)}</p>"]

    def image(self, img):
        return [_img(self.folder, img)]

    @staticmethod
    def table(headers, rows, caption, fold):
        out = []
        if fold:
            out.append(f"<details><summary>{_inline_md(_fold_summary(headers, rows, caption))}"
                       "</summary>")
        elif caption:
            out.append(f"<p class='caption'>{_inline_md(caption)}</p>")
        # a wide table scrolls inside its box; the page itself never scrolls sideways
        out += scroll_table([html.escape(h) for h in headers],
                            ["<tr>" + "".join(_td(cell(c)) for c in r) + "</tr>" for r in rows])
        if fold:
            out.append("</details>")
        return out


def html_page(title, sections, folder):
    """index.html: page.py's page of the sections."""
    return page(title, _walk(sections, _HtmlBlocks(folder)))


def write_text(folder, name, text):
    with open(os.path.join(folder, name), "w", encoding="utf-8") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())


def write_json(folder, name, obj):
    write_text(folder, name, json.dumps(obj, indent=1, allow_nan=False) + "\n")


class ReportExists(Exception):
    pass


def new_tmp_folder(results_dir):
    return tempfile.mkdtemp(prefix=".report.partial-", dir=results_dir)


def make_readable(folder):
    """The report is for others to read: the folder 0755 (mkdtemp made it 0700) and its files 0644,
    whatever the umask."""
    os.chmod(folder, FOLDER_MODE)
    for name in os.listdir(folder):
        path = os.path.join(folder, name)
        if os.path.isfile(path) and not os.path.islink(path):
            os.chmod(path, FILE_MODE)


def publish(tmp, results_dir, replace=False):
    """Move the finished temporary folder to RESULTS_DIR/report.

    Without replace: refuse (ReportExists) if report/ exists; the rename of a directory onto a
    missing name is atomic, so readers see either no report or a complete one.
    With replace: sdresults.replace_folder (the old report renamed aside, the new one into place,
    the old one deleted: report/ is never half-written, absent only for the instant between)."""
    final = os.path.join(results_dir, "report")
    make_readable(tmp)
    if os.path.lexists(final) and not replace:
        shutil.rmtree(tmp, ignore_errors=True)
        raise ReportExists(f"{final} exists (use --replace to replace it atomically)")
    replace_folder(tmp, final)
    return final


# ---------------------------------------------------------------- provenance, rerun commands
NOT_RECORDED = "not recorded"
REFERENCE_NAMES = {"dolfinx": "dolfinx", "freefem": "FreeFEM"}


def _text(v):
    """A provenance value as text; absent, null or empty: "not recorded"."""
    if v is None or v == "" or v == []:
        return NOT_RECORDED
    if isinstance(v, float) and not math.isfinite(v):
        return NOT_RECORDED
    return str(v)


def _command(argv, cwd=None):
    if not isinstance(argv, list) or not argv:
        return NOT_RECORDED
    import shlex

    out = "`" + shlex.join(str(a) for a in argv) + "`"
    if isinstance(cwd, str) and cwd:
        out += f" in `{cwd}`"
    return out


def provenance(summary, refs):
    """(report.json's `provenance`, table headers, table rows) of a results folder: sdcrack's
    `provenance` of summary.json and each reference's of its summary.json; a folder written before
    provenance was recorded gives null in JSON and "not recorded" in the table."""
    prov = summary.get("provenance")
    prov = prov if isinstance(prov, dict) else None
    ref_prov = {}
    for tool in sorted(refs):
        p = refs[tool]["summary"].get("provenance")
        ref_prov[tool] = p if isinstance(p, dict) else None
    headers = ["program", "version", "date (UTC)", "cores", "command line"]
    if prov is None:
        version = summary.get("sdcrack_version")
        rows = [["sdcrack", (f"{version}, " if version else "") + "provenance " + NOT_RECORDED
                 + " (summary.json written by an older sdcrack)", NOT_RECORDED, NOT_RECORDED,
                 NOT_RECORDED]]
    else:
        commit = prov.get("git_commit")
        version = _text(prov.get("sdcrack_version", summary.get("sdcrack_version")))
        if isinstance(commit, str) and commit:
            version += f", commit `{commit}`"
            dirty = prov.get("git_dirty")
            version += (" **(dirty: sources differ from the commit)**" if dirty is True
                        else "" if dirty is False else " (dirty flag not recorded)")
        else:
            version += ", not a git checkout"
        rows = [["sdcrack", version, _text(prov.get("date_utc")), _text(prov.get("cores")),
                 _command(prov.get("command_line"), prov.get("working_directory"))]]
    for tool, p in ref_prov.items():
        name = REFERENCE_NAMES.get(tool, tool)
        if p is None:
            rows.append([name, "provenance " + NOT_RECORDED + f" ({tool}/summary.json written by "
                         "an older reference script)", NOT_RECORDED, NOT_RECORDED, NOT_RECORDED])
            continue
        rows.append([name, f"{_text(p.get('tool') or tool)} {_text(p.get('tool_version'))} · "
                     f"Python {_text(p.get('python'))} · numpy {_text(p.get('numpy'))}",
                     _text(p.get("date_utc")), f"{_text(p.get('cores'))}; {threads_text(p)}",
                     _command(p.get("command_line"))])
    return {"sdcrack": prov, "references": ref_prov}, headers, rows


def threads_text(p):
    """What a reference's provenance `p` says of its BLAS/OpenMP threads (sdresults.PINNED_THREADS):
    pinned to 1, not pinned (which, and that a rerun, pinned, may then differ in the last digits),
    or not recorded."""
    from sdshared.sdresults import PINNED_THREADS, threads_pinned

    threads = p.get("threads")
    pinned = threads_pinned(threads)
    if pinned is None:
        return "BLAS/OpenMP threads " + NOT_RECORDED
    if pinned:
        return "BLAS/OpenMP threads pinned to 1"
    off = [f"{name}={threads[name]}" if threads.get(name) is not None else f"{name} unset"
           for name, value in PINNED_THREADS if threads.get(name) != value]
    return (f"BLAS/OpenMP threads not pinned ({', '.join(off)}): its rerun, pinned to 1, may "
            "differ from it in the last digits")


# A rerun writes where it is run from, never into the results tree: its --out is this folder,
# relative, unless tools/cases --rerun-dir names another one.
RERUN_FOLDER = "sdcrack-rerun"
# The flag of `sdcrack run` that solves without exporting meshes or running the references: a rerun
# of one case keeps the original's references unless asked to rerun them (the flag dropped).
SOLVER_ONLY = "--solver-only"
CHECKOUT_BINARY = ("target", "release", "sdcrack")


def rerun_executable(summary, checkout=None):
    """The binary a rerun command names. For a results folder (summary.json's dict): the binary
    that wrote it (provenance `executable`, when recorded and absolute), else `sdcrack` from PATH.
    For a scene file (`summary` None): the checkout's target/release/sdcrack under `checkout`.
    One home for the reports (rerun_command) and tools/cases."""
    if summary is None:
        return os.path.join(checkout, *CHECKOUT_BINARY)
    prov = summary.get("provenance") if isinstance(summary, dict) else None
    exe = prov.get("executable") if isinstance(prov, dict) else None
    return exe if isinstance(exe, str) and os.path.isabs(exe) else "sdcrack"


def rerun_command(results_dir, summary, scene_file, k, rerun_dir=None):
    """The shell command that reruns one case of this results folder: the binary that wrote it
    (rerun_executable), the folder's own copy of the scene (RESULTS_DIR/scene.toml, absolute), the
    case's level, u space and multiplier (and `--p-mass lumped` for a lumped case, `--p-space
    broken-tangential` for a broken-tangential one) with the δ sweep of the run (each δ
    warm-started from the previous one, as in the run, so the numbers come back exactly; `--delta`
    only when the run was restricted to one δ), into rerun_out(rerun_dir, ...): by default the
    relative folder sdcrack-rerun/<scene>-l<L>-<u>-<m>[-lumped][-ptangential][-d<δ>] of the
    directory it is run from. The command tools/cases prints for the same folder."""
    from .settings import scene_lists

    plan_deltas = sorted({float(d) for d in ((summary.get("plan") or {}).get("deltas") or [])})
    restricted = plan_deltas != sorted(set(scene_lists(scene_file)[3]))
    return rerun_args(rerun_executable(summary),
                      os.path.join(os.path.abspath(results_dir), "scene.toml"),
                      summary.get("scene", "scene"), k, k["delta"] if restricted else None,
                      rerun_dir, scene_references(scene_file))


def scene_references(scene_file):
    """The reference tools a scene file (parsed) lists, [outputs] references."""
    refs = (scene_file.get("outputs") or {}).get("references") if isinstance(scene_file, dict) \
        else None
    return [str(t) for t in refs] if isinstance(refs, list) else []


def rerun_out(rerun_dir, name):
    """The --out of a rerun named `name`: RERUN_FOLDER/name, relative, so that it lands under the
    directory the command is run from; RERUN_DIR/name (absolute) when a folder is given."""
    if rerun_dir is None:
        return os.path.join(RERUN_FOLDER, name)
    return os.path.join(os.path.abspath(rerun_dir), name)


def rerun_args(exe, scene_path, scene_name, k, only_delta, rerun_dir=None, references=()):
    """The shell command `env THREADS... exe run SCENE_PATH` of one rerunnable unit `k` (level,
    u space, multiplier, p mass, p space; absent p_mass / p_space: consistent / continuous): the
    whole δ sweep, or `--delta` alone when `only_delta` is given, into
    rerun_out(RERUN_DIR, <scene>-l<L>-<u>-<m>[-lumped][-ptangential][-d<δ>]) (the suffixes of the
    solver's field names), with the BLAS/OpenMP threads the campaign's jobs run with
    (sdresults.PINNED_THREADS). A scene with `references` gets `--solver-only`: the unit alone is
    rerun, the original's references are not (a rerun of them is asked for by dropping the flag:
    then the level's references run too, pinned alike). One home for the commands of the reports
    and of tools/cases."""
    import shlex

    from sdshared.sdresults import pinned_env_args

    args = pinned_env_args() + [exe, "run", scene_path] + ([SOLVER_ONLY] if references else []) \
        + ["--level", str(k["level"]), "--u-space", str(k["u_space"]),
           "--multiplier", str(k["multiplier"])]
    name = f"{scene_name}-l{k['level']}-{k['u_space']}-{k['multiplier']}"
    pm, ps = p_mass(k), p_space(k)
    if pm != DEFAULT_P_MASS:  # the consistent command is the one of a run without p masses
        args += ["--p-mass", pm]
        name += f"-{pm}"
    if ps != DEFAULT_P_SPACE:  # the continuous command is the one of a run without p spaces
        args += ["--p-space", ps]
        name += f"-{p_space_tag(ps)}"
    if only_delta is not None:
        d = fmt_delta(only_delta)
        args += ["--delta", d]
        name += f"-d{d}"
    args += ["--out", rerun_out(rerun_dir, name)]
    return shlex.join(args)


def rerun_compare_command(results_dir, rerun="<name>"):
    """The command comparing a rerun of this results folder with it (compare/sdcompare-rerun of
    the sdcrack checkout, compare/sdcompare_lib/rerun_diff.py): the folder by absolute path, the
    rerun by the relative --out of its command, RERUN_FOLDER/<name>."""
    import shlex

    return (f"compare/sdcompare-rerun {shlex.quote(os.path.abspath(results_dir))} "
            f"{os.path.join(RERUN_FOLDER, rerun)}")
