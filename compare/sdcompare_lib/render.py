"""Report rendering (Markdown + self-contained HTML + JSON) and the atomic report folder write.

A report is a list of sections: dict(title, paras=[str], tables=[(headers, rows)], images=[png],
paras_after=[str]).
"""
import base64
import html
import json
import os
import shutil
import tempfile


def fmt(v, spec=".3e"):
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "**NO**"
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


def fmt_rate(v):
    return "–" if v is None else f"{v:.2f}"


def markdown(title, sections):
    out = [f"# {title}", ""]
    for s in sections:
        out += [f"## {s['title']}", ""]
        for p in s.get("paras", []):
            out += [p, ""]
        for headers, rows in s.get("tables", []):
            if not rows:
                continue
            out.append("| " + " | ".join(headers) + " |")
            out.append("|" + "---|" * len(headers))
            for r in rows:
                out.append("| " + " | ".join(str(c) for c in r) + " |")
            out.append("")
        for img in s.get("images", []):
            out += [f"![{img}]({img})", ""]
        for p in s.get("paras_after", []):
            out += [p, ""]
    return "\n".join(out)


def _inline_md(text):
    t = html.escape(text)
    parts = t.split("**")
    t = "".join(f"<b>{p}</b>" if i % 2 else p for i, p in enumerate(parts))
    parts = t.split("`")
    return "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))


def html_page(title, sections, folder):
    css = ("body{font-family:sans-serif;max-width:1200px;margin:auto;padding:1em}"
           "table{border-collapse:collapse;margin:0.5em 0;font-size:13px}"
           "td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}"
           "th{background:#eee}.PASS{color:#070;font-weight:bold}.FAIL{color:#b00;font-weight:bold}"
           "img{max-width:100%}code{font-size:11px;text-align:left}")
    out = ["<!DOCTYPE html>", "<html><head><meta charset='utf-8'>",
           f"<title>{html.escape(title)}</title><style>{css}</style></head><body>",
           f"<h1>{html.escape(title)}</h1>"]
    for s in sections:
        out.append(f"<h2>{html.escape(s['title'])}</h2>")
        for p in s.get("paras", []):
            out.append(f"<p>{_inline_md(p)}</p>")
        for headers, rows in s.get("tables", []):
            if not rows:
                continue
            out.append("<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in headers)
                       + "</tr>")
            for r in rows:
                out.append("<tr>" + "".join(f"<td>{_inline_md(str(c))}</td>" for c in r) + "</tr>")
            out.append("</table>")
        for img in s.get("images", []):
            with open(os.path.join(folder, img), "rb") as fh:
                b64 = base64.b64encode(fh.read()).decode("ascii")
            out.append(f"<p><img alt='{html.escape(img)}' src='data:image/png;base64,{b64}'></p>")
        for p in s.get("paras_after", []):
            out.append(f"<p>{_inline_md(p)}</p>")
    out.append("</body></html>")
    return "\n".join(out)


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


def publish(tmp, results_dir, replace=False):
    """Move the finished temporary folder to RESULTS_DIR/report.

    Without replace: refuse (ReportExists) if report/ exists; the rename of a directory onto a
    missing name is atomic, so readers see either no report or a complete one.
    With replace: the old report is first renamed to a hidden name, then the new one is renamed
    into place, then the old one is deleted (two atomic renames; report/ is never half-written,
    but it is absent for the instant between them)."""
    final = os.path.join(results_dir, "report")
    if os.path.lexists(final):
        if not replace:
            shutil.rmtree(tmp, ignore_errors=True)
            raise ReportExists(f"{final} exists (use --replace to replace it atomically)")
        old = tempfile.mkdtemp(prefix=".report.old-", dir=results_dir)
        os.rename(final, os.path.join(old, "report"))
        os.rename(tmp, final)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.rename(tmp, final)
    return final
