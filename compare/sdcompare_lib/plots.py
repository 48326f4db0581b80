"""PNG plots (matplotlib, Agg backend). Each function returns the file name written or None."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

QLABEL = {"u_l2": "‖u_h−u‖_L²", "p_l2": "‖p_h−∇u‖_L²", "p_x": "‖p_h−∇u‖_X", "lambda_l2": "‖λ_h−[u]‖_L²(Γc)"}
STYLE = {"broken": "-", "continuous": "--"}
MARK = {"M0": "o", "M1": "s", "M1star": "^"}


def _legend(ax):
    """A legend only when something was drawn with a label (e.g. no δ-differences on a fully
    closed crack, where λ_δ = λ_0 = 0)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7)


def _save(fig, folder, name):
    path = os.path.join(folder, name)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return name


def _positive(e):
    return e is not None and e > 0


def rate_plot(folder, scene, rate_entries):
    """Errors against h per quantity (u = the exact or the reference solution, per the series'
    `against`); a series that does not converge is marked in its label by its status."""
    ents = [r for r in rate_entries if any(_positive(e) for e in r["errors"])]
    if not ents:
        return None
    qs = [q for q in QLABEL if any(r["quantity"] == q for r in ents)]
    fig, axes = plt.subplots(1, len(qs), figsize=(4.6 * len(qs), 4), squeeze=False)
    for ax, q in zip(axes[0], qs):
        for r in (r for r in ents if r["quantity"] == q):
            pts = [(h, e) for h, e in zip(r["h"], r["errors"]) if _positive(e)]
            if not pts:
                continue
            ax.loglog(*zip(*pts), STYLE.get(r["u_space"], ":"), marker=MARK.get(r["multiplier"], "x"),
                      label=f"{r['u_space']}/{r['multiplier']}"
                      + ("" if r["status"] == "converges" else f" ({r['status']})"))
        h = [x for r in ents for x in r["h"]]
        if h:
            h0, h1 = max(h), min(h)
            ref = [e for r in ents if r["quantity"] == q for e in r["errors"] if _positive(e)]
            if ref:
                e0 = min(ref)
                for p in (0.5, 1.0, 2.0):
                    ax.loglog([h0, h1], [e0 * 4, e0 * 4 * (h1 / h0) ** p], "k:", lw=0.7)
                    ax.annotate(f"h^{p:g}", (h1, e0 * 4 * (h1 / h0) ** p), fontsize=7)
        ax.set_xlabel("h")
        against = sorted({r["against"] for r in ents if r["quantity"] == q and r["against"]})
        ax.set_title(f"{scene}: {QLABEL[q]}" + (f", u = {' / '.join(against)}" if against else ""))
        ax.grid(True, which="both", alpha=0.3)
        _legend(ax)
    return _save(fig, folder, f"rates-{scene}.png")


def delta_plot(folder, scene, delta_entries):
    if not delta_entries:
        return None
    levels = sorted({d["level"] for d in delta_entries})
    lvl = levels[-1]
    qs = [q for q in ("u_l2", "p_l2", "lambda_l2") if any(d["quantity"] == q for d in delta_entries)]
    fig, axes = plt.subplots(1, len(qs), figsize=(4.6 * len(qs), 4), squeeze=False)
    for ax, q in zip(axes[0], qs):
        for d in delta_entries:
            if d["quantity"] != q or d["level"] != lvl:
                continue
            pts = [(x, y) for x, y in zip(d["deltas"], d["diffs"]) if x > 0 and y > 0]
            if pts:
                s = d["slope"]
                ax.loglog(*zip(*pts), STYLE.get(d["u_space"], ":"), marker=MARK.get(d["multiplier"], "x"),
                          label=f"{d['u_space']}/{d['multiplier']} slope "
                                + ("–" if s is None else f"{s:.2f}"))
        ax.set_xlabel("δ")
        ax.set_title(f"{scene} level {lvl}: ‖{q.split('_')[0]}_δ − {q.split('_')[0]}_0‖")
        ax.grid(True, which="both", alpha=0.3)
        _legend(ax)
    return _save(fig, folder, f"delta-{scene}.png")


def work_precision_plot(folder, scene, timing_rows, ref_rows):
    pts = [t for t in timing_rows if t["u_l2"] is not None and t["u_l2"] > 0 and t["total_s"] > 0]
    rpts = [r for r in ref_rows if (r.get("errors") or {}).get("u_l2") and r.get("total_s")]
    if not pts and not rpts:
        return None
    fig, ax = plt.subplots(figsize=(6, 4.5))
    variants = sorted({(t["u_space"], t["multiplier"]) for t in pts})
    for u, m in variants:
        sel = sorted((t for t in pts if t["u_space"] == u and t["multiplier"] == m
                      and t["delta"] == min(x["delta"] for x in pts)), key=lambda t: t["level"])
        if sel:
            ax.loglog([t["total_s"] for t in sel], [t["u_l2"] for t in sel], STYLE.get(u, ":"),
                      marker=MARK.get(m, "x"), label=f"{u}/{m}")
    for tool in sorted({r["tool"] for r in rpts}):
        sel = sorted((r for r in rpts if r["tool"] == tool), key=lambda r: r["level"])
        ax.loglog([r["total_s"] for r in sel], [r["errors"]["u_l2"] for r in sel], "k-.",
                  marker="*", label=f"reference {tool}")
    ax.set_xlabel("total time per case [s] (sum of timings_s)")
    ax.set_ylabel("‖u − u_ex‖_L²")
    ax.set_title(f"{scene}: work–precision")
    ax.grid(True, which="both", alpha=0.3)
    _legend(ax)
    return _save(fig, folder, f"work-precision-{scene}.png")


def delta_reference_plot(folder, scene, agreement):
    """Distance to the reference of the same level as δ decreases: it falls with δ until it reaches
    the discretisation floor of the level (the δ = 0 value, dotted), and the floor falls with h."""
    rows = [a for a in agreement if a["kind"] == "solver_vs_reference" and a.get("e_u") is not None]
    if not rows:
        return None
    tool = sorted({a["reference"] for a in rows})[0]
    mult = sorted({a["multiplier"] for a in rows})[-1]
    spaces = sorted({a["u_space"] for a in rows})
    fig, axes = plt.subplots(1, len(spaces), figsize=(5.2 * len(spaces), 4), squeeze=False)
    for ax, u in zip(axes[0], spaces):
        sel = [a for a in rows if a["reference"] == tool and a["multiplier"] == mult and a["u_space"] == u]
        deltas = sorted({a["delta"] for a in sel if a["delta"] > 0})
        if not deltas:
            continue
        for lvl in sorted({a["level"] for a in sel}):
            pts = sorted((a["delta"], a["e_u"]) for a in sel if a["level"] == lvl and a["delta"] > 0)
            floor = [a["e_u"] for a in sel if a["level"] == lvl and a["delta"] == 0]
            line = ax.loglog(*zip(*pts), marker="o", label=f"level {lvl}")[0] if pts else None
            if floor and line is not None:
                ax.axhline(floor[0], color=line.get_color(), ls=":", lw=0.8)
        ax.set_xlabel("δ (dotted: δ = 0, the floor of the level)")
        ax.set_title(f"{scene}: ‖u_δh − u_{tool}‖_L², {u}/{mult}")
        ax.grid(True, which="both", alpha=0.3)
        _legend(ax)
    return _save(fig, folder, f"delta-reference-{scene}.png")
