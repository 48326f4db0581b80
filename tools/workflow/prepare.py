#!/usr/bin/python3
"""Prepares a campaign folder's inputs/ for tools/workflow/Snakefile (called by tools/campaign).

    prepare.py --out DIR --bin SDCRACK --repo ROOT [--levels A-B] [--threads N]
               [--memory-scale F] [--baseline OLD_DIR] [--expectations FILE] [--dry-run]
               SCENE.toml...

Writes, under DIR/inputs/:
  sdcrack, sdcrack.sha256  a copy of the binary and its sha256, replaced only when the sha256
                           differs (every job depends on sdcrack.sha256: a rebuilt binary reruns all)
  <name>.toml              each scene file, its `levels = [...]` line replaced when --levels is
                           given; rewritten only when its bytes change (mtimes move on real change)
  config.json              the workflow's config: repo, scenes, each scene's plan (`sdcrack check
                           --json`), expectations, baselines, solver threads, the factor
                           on every job's memory request (--memory-scale, default 1)
and removes leftovers of killed merges (DIR/.<name>.partial-<pid>/; the caller holds the lock).

--dry-run writes only what is missing (so that a dry run does not move the mtimes a later run
compares) and its config as config.dry-run.json; an existing input whose bytes would change is
left alone and the outputs depending on it are listed in that config's `forcerun` for
`snakemake --forcerun`.

Prints the number of jobs of the whole campaign on stdout. Bad input: one line on stderr, exit 2.
Standard library only (/usr/bin/python3).
"""

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib

from sdshared.sdresults import write_atomic

RESERVED = {"inputs", "shards", "checks", "logs", "benchmarks", "index.html", "index.json"}
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._+-]*$")
LEVELS_RE = re.compile(r"(?m)^levels[ \t]*=[ \t]*\[[^\]\n]*\][ \t]*$")


class Refused(Exception):
    """A one-line error for the user (exit 2)."""


MESH_RE = re.compile(r'(gmsh[ \t]*=[ \t]*)"([^"\n]*)"')


def with_absolute_mesh(scene, text, data):
    """The scene's `mesh = { gmsh = "file.msh" }` made absolute (relative to the scene file, as
    sdcrack reads it), so the copy in DIR/inputs/ finds the file; a comment line with the mesh
    file's sha256 makes a changed mesh a changed input. (text, bytes), unchanged without a mesh."""
    m = MESH_RE.search(text)
    if not m:
        return text, data
    path = os.path.join(os.path.dirname(os.path.abspath(scene)), m.group(2))
    digest = sha256(path) if os.path.isfile(path) else "missing"
    text = (text[:m.start()] + m.group(1) + json.dumps(os.path.abspath(path)) + text[m.end():]
            + f"\n# mesh file sha256: {digest}\n")
    return text, text.encode("utf-8")


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def read_bytes(path):
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except FileNotFoundError:
        return None


def parse_levels(text):
    m = re.fullmatch(r"(\d+)(?:-(\d+))?", text)
    if not m:
        raise Refused(f"--levels {text}: expected A-B (e.g. 0-5) or one level")
    a = int(m.group(1))
    b = int(m.group(2)) if m.group(2) is not None else a
    if b < a:
        raise Refused(f"--levels {text}: the first level is larger than the last")
    return list(range(a, b + 1))


# The p spaces of sdcrack (`--p-space`) and the suffix each adds to its solver shard's and job's
# names: none for the paper's continuous p, so that a plan without the axis has the names of before
# it; "-ptangential" after the p mass for the broken-tangential p, as in the solver's field names
# (level3-broken-M1-lumped-ptangential-delta0).
P_SPACE_SUFFIX = {"continuous": "", "broken-tangential": "-ptangential"}


def served(u_space, p_space):
    """Whether sdcrack runs this u space with this p space: the broken-tangential p only with the
    broken u (`sdcrack run --u-space continuous --p-space broken-tangential` exits 2)."""
    return not (u_space == "continuous" and p_space == "broken-tangential")


def plan_p_spaces(plan):
    """The plan's p spaces (["continuous"] for a plan of before the axis)."""
    return list(plan.get("p_spaces") or ["continuous"])


def solver_units(plan, level=None, u_space=None):
    """(level, u space, multiplier, p mass, p space) of each solver job of the plan, in the order
    levels × u spaces × multipliers × p masses × p spaces, the pairs sdcrack does not run left out;
    only those of `level` and `u_space` when given (a check job's shards)."""
    return [(lv, u, m, pm, ps)
            for lv in plan["levels"] if level is None or int(lv) == int(level)
            for u in plan["u_spaces"] if u_space is None or u == u_space
            for m in plan["multipliers"] for pm in plan["p_masses"]
            for ps in plan_p_spaces(plan) if served(u, ps)]


def solver_shard(name, level, u, m, pm, ps):
    """The solver job's shard folder shards/<name>/solver/l<L>-<u>-<m>-<pm>[-ptangential]."""
    return f"shards/{name}/solver/l{level}-{u}-{m}-{pm}{P_SPACE_SUFFIX[ps]}"


# The problem kind `sdcrack check --json` names for an elastic scene (no "problem" key: the scalar
# problem, as in summary.json).
ELASTIC = "elasticity"


def is_elastic(plan):
    """Whether the plan is an elastic scene's (docs/elasticity.md): its solver jobs are the
    smooth-domain method's (elastic_solver_units), it has no check job, and a report of its own
    kind."""
    return plan.get("problem") == ELASTIC


def elastic_solver_units(plan, level=None):
    """(level, multiplier) of each solver job of an elastic plan, levels × multipliers (only
    those of `level` when given); none for a scene that lists no solver case (no multipliers and
    no deltas) or for a scalar plan. A job runs its (level, multiplier)'s whole δ sweep, as a
    scalar solver job does: `afw::AfwCase` assembles and factors once per level for every δ."""
    if not is_elastic(plan):
        return []
    return [(lv, m) for lv in plan["levels"] if level is None or int(lv) == int(level)
            for m in plan["multipliers"]]


def elastic_solver_shard(name, level, m):
    """The elastic solver job's shard folder shards/<name>/solver/l<L>-elasticity-<m> (the
    problem kind where a scalar shard has its u space, as the case's series name
    level<L>-elasticity-<m> in fields.h5)."""
    return f"shards/{name}/solver/l{level}-{ELASTIC}-{m}"


def solver_shards(plan):
    """Every solver job's shard folder of the plan, scalar (solver_units) or elastic
    (elastic_solver_units), in the order of the units."""
    name = plan["name"]
    return ([solver_shard(name, *unit) for unit in solver_units(plan)]
            + [elastic_solver_shard(name, *unit) for unit in elastic_solver_units(plan)])


def reference_shards(plan, level=None):
    """The reference jobs' shard folders shards/<name>/<tool>/l<L>, tools × levels (only `level`'s
    when given: a check job's shards)."""
    return [f"shards/{plan['name']}/{tool}/l{lv}" for tool in plan["references"]
            for lv in plan["levels"] if level is None or int(lv) == int(level)]


def check_files(plan):
    """The check jobs' files: one per level and u space, one per level for the references; none
    for a scene without [exact] (its report recomputes no error) and none for an elastic scene
    (`sdcompare --precompute` reads the scalar problem's shards only: the elastic report computes
    its errors itself)."""
    name = plan["name"]
    if not plan.get("exact", True) or is_elastic(plan):
        return []
    checks = [f"checks/{name}/solver-l{lv}-{u}.json" for lv in plan["levels"]
              for u in plan["u_spaces"]]
    if plan["references"]:
        checks += [f"checks/{name}/references-l{lv}.json" for lv in plan["levels"]]
    return checks


def jobs_of(plan):
    """(solver shard folders, reference shard folders, check files (check_files), report folder)
    of one scene's plan. An elastic scene's solver jobs are its (level, multiplier) units (none
    when the scene lists no solver case)."""
    return solver_shards(plan), reference_shards(plan), check_files(plan), plan["name"]


# The memory a job asks for (`mem_mb`, Slurm's --mem under --profile slurm; docs/workflow.md,
# "Memory"), MB: its own estimate plus what Snakemake itself takes in a cluster job. A solver job's
# own is sdcrack's estimate of its level (`sdcrack check --json`'s memory_mb); a Python job's, its
# interpreter and libraries (PYTHON_JOB_MB) plus the part of that estimate that grows with the
# mesh (mesh_memory_mb; the report: of the scene's finest level). The bases, from the peaks
# measured by Snakemake in the nightly of 2026-11-26 (levels 0-5, tests/data/nightly-peaks.tsv)
# and by sacct at levels 0-2: dolfinx 208 (Python, dolfinx and MPI: up to 199.5 MB), FreeFEM 96
# (Python and FreeFem++), a check 128 (numpy, h5py), the report 256 (sdcrack merge, then the
# compare tool with matplotlib: 253 MB at the least). In a Slurm job the plugin runs Snakemake
# twice, in the batch step and, through srun, around the command: ~130 MB each (sacct on
# ci/slurm-local: 135 and 123 MB, Snakemake 9.27.1), SNAKEMAKE_JOB_MB together.
SNAKEMAKE_JOB_MB = 300
PYTHON_JOB_MB = {"dolfinx": 208, "freefem": 96, "check": 128, "report": 256}


# An elastic scene's report (compare/sdcompare_lib/elastic_report.py) holds both references'
# vector fields and their stresses on the finest mesh, with the exact fields at its quadrature
# points: its part that grows with the mesh is counted twice. Measured (Snakemake, 2026-11-28,
# elastic-williams-open at levels 0-5, 8 x 8 cells: level 5 is 131 072 triangles): the report's
# peak 890 MB, above the scalar report's estimate of 256 + 600 = 856 MB; 256 + 2 x 600 = 1456 MB.
# Its reference jobs keep the scalar references' estimates: dolfinx 208 + 600 = 808 MB for a
# peak of 607 MB at level 5, FreeFEM 96 + 600 = 696 MB for 340 MB (docs/workflow.md, "Memory").
ELASTIC_REPORT_MESH_FACTOR = 2

# An elastic solver job (the smooth-domain method, `sdcrack run --level L --multiplier M`) factors
# the AFW system (4 σ dofs per edge, 2 u and 1 γ per triangle, symmetric indefinite LDLᵀ): several
# times the scalar solver's memory per cell, which `sdcrack check --json`'s memory_mb estimates. Its own
# estimate counts the part that grows with the mesh (mesh_memory_mb) ELASTIC_SOLVER_MESH_FACTOR
# times. Measured (/usr/bin/time's maximum resident set, `--solver-only`, 2026-11-28, machine
# loaded) on elastic-williams-open (8 x 8 cells, uniform) and its graded twin (β = 0.4), peak MB
# against mesh_memory_mb: uniform level 3 163 (29), 4 547 (132), 5 2309 (600); graded level 3
# 199 (39), 4 677 (187), 5 2772 (866). The per-cell factor of the solve grows with the fill of the
# factor (n log n cells and more): (peak − 128) / mesh_memory_mb is 1.2–1.8 at level 3, 2.9–3.2
# at level 4, 3.6 (uniform) and 3.1 (graded) at level 5; 4 holds every peak, the
# largest estimate / peak 1.5 (level 3: 244 / 163; the campaign adds SNAKEMAKE_JOB_MB).
ELASTIC_SOLVER_MESH_FACTOR = 4


def own_memory_mb(job, plan, level=None):
    """A job's own memory estimate, MB: `job` is solver, dolfinx, freefem, check or report (no
    level: the scene's finest); `plan` the scene's `sdcrack check --json`."""
    if job == "solver":
        own = int(plan["memory_mb"][str(level)])
        if is_elastic(plan):
            own += (ELASTIC_SOLVER_MESH_FACTOR - 1) * int(plan["mesh_memory_mb"][str(level)])
        return own
    if job == "report":
        factor = ELASTIC_REPORT_MESH_FACTOR if is_elastic(plan) else 1
        return PYTHON_JOB_MB[job] + factor * max(int(v) for v in plan["mesh_memory_mb"].values())
    return PYTHON_JOB_MB[job] + int(plan["mesh_memory_mb"][str(level)])


def memory_request_mb(own_mb):
    """What a job with the own estimate `own_mb` asks for, MB (before --memory-scale)."""
    return own_mb + SNAKEMAKE_JOB_MB


def check_scene(exe, path):
    r = subprocess.run([exe, "check", path, "--json"], capture_output=True, text=True)
    if r.returncode != 0:
        lines = [x for x in (r.stderr or r.stdout).splitlines() if x.strip()]
        raise Refused(lines[-1] if lines else f"sdcrack check exited {r.returncode}")
    try:
        plan = json.loads(r.stdout)
    except ValueError as exc:
        raise Refused(f"sdcrack check --json printed no JSON object: {exc}") from None
    for key in ("name", "levels", "u_spaces", "multipliers", "p_masses", "p_spaces", "references",
                "memory_mb", "mesh_memory_mb"):
        if key not in plan:
            raise Refused(f"sdcrack check --json lacks `{key}` (binary too old?)")
    unknown = [ps for ps in plan["p_spaces"] if ps not in P_SPACE_SUFFIX]
    if unknown:
        raise Refused(f"p space {unknown[0]!r} unknown to the campaign workflow "
                      f"(it knows {', '.join(P_SPACE_SUFFIX)})")
    return plan


def prepare(args):
    out = os.path.abspath(args.out)
    inputs = os.path.join(out, "inputs")
    os.makedirs(inputs, exist_ok=True)
    forcerun = []

    # the binary: copied (the jobs run inputs/sdcrack, so a rebuild during a campaign cannot mix
    # binaries) and replaced only when its sha256 differs
    if not os.access(args.bin, os.X_OK) or os.path.isdir(args.bin):
        raise Refused(f"{args.bin}: no sdcrack binary there (build it, or set SDCRACK_BIN)")
    digest = sha256(args.bin)
    exe = os.path.join(inputs, "sdcrack")
    sha_file = os.path.join(inputs, "sdcrack.sha256")
    have = read_bytes(sha_file)
    binary_changed = False
    if have is None or have.decode(errors="replace").split()[:1] != [digest] \
            or not os.path.isfile(exe) or sha256(exe) != digest:
        if args.dry_run and have is not None:
            binary_changed = True  # left alone: the dry run forces everything instead
        else:
            write_atomic(exe, read_bytes(args.bin), 0o755)
            write_atomic(sha_file, f"{digest}  sdcrack\n".encode())
    check_exe = exe if os.path.isfile(exe) and not binary_changed else os.path.abspath(args.bin)

    levels = parse_levels(args.levels) if args.levels else None
    plans, sources, changed = {}, {}, set()
    for scene in args.scenes:
        data = read_bytes(scene)
        if data is None:
            raise Refused(f"{scene}: no such scene file")
        text = data.decode("utf-8", errors="replace")
        text, data = with_absolute_mesh(scene, text, data)
        if levels is not None:
            text, n = LEVELS_RE.subn(f"levels = [{', '.join(map(str, levels))}]", text)
            if n != 1:
                raise Refused(f"{scene}: no single `levels = [...]` line to replace for --levels")
            data = text.encode("utf-8")
        tmp = os.path.join(inputs, f".check-{os.getpid()}.toml")
        write_atomic(tmp, data)
        try:
            plan = check_scene(check_exe, tmp)
        except Refused as exc:  # sdcrack names the file it checked: name the user's instead
            raise Refused(f"{scene}: {str(exc).replace(tmp, scene)}") from None
        finally:
            os.unlink(tmp)
        name = plan["name"]
        if not NAME_RE.match(name) or name in RESERVED:
            raise Refused(f"{scene}: scene name '{name}' cannot name a campaign folder "
                          f"(letters, digits, . _ + - only; not {', '.join(sorted(RESERVED))})")
        if name in plans:
            raise Refused(f"{scene}: two scenes named '{name}' ({sources[name]} and {scene})")
        # whether the compare tool has errors to recompute: the check jobs run for [exact] scenes
        try:
            plan["exact"] = "exact" in tomllib.loads(text)
        except tomllib.TOMLDecodeError:  # sdcrack check accepted it: not expected
            plan["exact"] = True
        plans[name], sources[name] = plan, scene
        target = os.path.join(inputs, f"{name}.toml")
        old = read_bytes(target)
        if old != data:
            if args.dry_run and old is not None:
                changed.add(name)
            else:
                write_atomic(target, data)
    if not plans:
        raise Refused("no scene to run")

    total = 0
    for name, plan in plans.items():
        solver, refs, checks, report = jobs_of(plan)
        total += len(solver) + len(refs) + len(checks) + 1
        if binary_changed or name in changed:
            forcerun += solver + refs + checks + [report]

    baselines = {}
    if args.baseline:
        for name in plans:
            b = os.path.join(os.path.abspath(args.baseline), name)
            # an elastic report has no baseline section (sdcompare refuses --baseline for it);
            # the index still lists what changed since (tools/campaign_index.py --baseline)
            if os.path.isdir(b) and not is_elastic(plans[name]):
                baselines[name] = b
    expectations = os.path.abspath(args.expectations or
                                   os.path.join(args.repo, "scenes", "expectations.toml"))
    if not os.path.isfile(expectations):
        raise Refused(f"{expectations}: no expectations file")
    config = {
        "repo": os.path.abspath(args.repo),
        "scenes": list(plans),
        "scene_files": {n: os.path.abspath(s) for n, s in sources.items()},
        "plans": plans,
        "expectations": expectations,
        "baselines": baselines,
        "threads": args.threads,
        "memory_scale": args.memory_scale,
        "jobs": total,
        "forcerun": forcerun,
    }
    write_atomic(os.path.join(inputs, "config.dry-run.json" if args.dry_run else "config.json"),
                 (json.dumps(config, indent=1) + "\n").encode())

    # merges killed before their rename leave DIR/.<name>.partial-<pid>/; nothing reads them
    if not args.dry_run:
        for entry in os.listdir(out):
            if re.fullmatch(r"\..+\.partial-\d+", entry):
                shutil.rmtree(os.path.join(out, entry), ignore_errors=True)
    return total


def positive_float(text):
    """argparse's type of --memory-scale: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"{text}: expected a number > 0")
    return value


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenes", nargs="+")
    p.add_argument("--out", required=True)
    p.add_argument("--bin", required=True)
    p.add_argument("--repo", required=True)
    p.add_argument("--levels")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--memory-scale", type=positive_float, default=1.0)
    p.add_argument("--baseline")
    p.add_argument("--expectations")
    p.add_argument("--dry-run", action="store_true")
    args = p.parse_args()
    try:
        print(prepare(args))
    except Refused as exc:
        print(f"campaign: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
