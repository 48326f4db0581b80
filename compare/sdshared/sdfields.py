"""Field files of the reference solvers: fields.h5 in the layout of the solver's writer
(crates/sdcrack-io/src/output/xdmf.rs), one grid per level on the cracked mesh, and one XDMF file per grid, so
ParaView, meshio and the compare tool read solver and references alike.

    fields.h5   /meshes/level{L}/points (N,3)   /meshes/level{L}/triangles (T,3) int64
                /cases/level{L}/<point field>   scalar (N,) or vector (N,3): u, and p = ∇u_h at the
                vertices (vertex_gradient) in both references; the elastic references (docs/
                elasticity.md): u (N,3) with u_z = 0, and the cell field stress (T,3)
                /cases/level{L}/crack/points (I,3)  /crack/segments (S,2)  /crack/<crack field> (I,)
                (the crack nodes of every crack in crack.txt's row order; segments: the row pairs
                [k, k+1] within each crack, none joining two cracks, S = I − number of cracks); the
                references' crack fields: `jump` = u⁺ − u⁻ (crack.txt's plus minus minus row) and
                `contact_force` = the nodal multiplier λ_j ≥ 0 of the QP (0 off the active set and
                at the tips), a name per quantity shared with the solver's files (README's field
                table); older files call the contact force `multiplier`, which
                crack_field() still reads
                every dataset has the attributes "level" (int), "tool" (str) and, when the caller
                gives it, "h" (float, the level's mesh size); the file has the attribute "tool"
    fields/level{L}.xdmf         XDMF 3, the Triangle grid "level{L}" with the point fields
    fields/level{L}.crack.xdmf   XDMF 3, the Polyline grid "level{L}/crack" with the crack fields, one
                                 line cell per segment (one grid a file: meshio reads them, ParaView
                                 opens them as they are)

The solver's convention (crates/sdcrack-io/src/output/xdmf.rs): `NAME.xdmf` holds one state, a single grid that
meshio.read reads; `NAME.series.xdmf` a temporal collection for meshio's TimeSeriesReader. A
reference solves one state per level, so it writes only the first kind.

There is no top-level fields.xdmf: a spatial collection of all levels' grids (they overlap) showed
as one grey square in ParaView and meshio.read could not read it.
"""

import numpy as np

# Old names of crack fields, by current name: what older files call them (the
# references' contact force was `multiplier`, a name that sdcrack's files use for the multiplier
# space M0 / M1 / M1star of a case).
OLD_NAMES = {"contact_force": ("multiplier",)}


def crack_field(fields, name):
    """The crack field `name` (an np.ndarray) of `fields`: an h5py crack group
    (/cases/level{L}/crack), meshio's point_data of a .crack.xdmf, or any mapping of names to arrays;
    under its current name, else under an old one of OLD_NAMES (a file written before the rename).
    KeyError naming every name tried when it has none of them."""
    tried = (name,) + OLD_NAMES.get(name, ())
    for key in tried:
        if key in fields:
            return np.asarray(fields[key][()])
    raise KeyError(f"no crack field {' or '.join(map(repr, tried))} (have {', '.join(sorted(fields))})")


def vertex_gradient(xy, tri, u):
    """p = ∇u_h at the cracked vertices (N, 2), the point field `p` of both references: the
    area-weighted mean of the constant triangle gradients of the P1 u_h (each copy of a crack vertex
    averages its own face's triangles)."""
    g, det = _gradients_and_det(xy, tri, u)
    area = np.abs(det) / 2
    acc, wsum = np.zeros((len(xy), 2)), np.zeros(len(xy))
    for k in range(3):
        np.add.at(acc, tri[:, k], g * area[:, None])
        np.add.at(wsum, tri[:, k], area)
    return acc / np.maximum(wsum, 1e-300)[:, None]


def triangle_gradients(xy, tri, u):
    """(T, 2) the constant gradient of the P1 field u (N,) on each triangle."""
    return _gradients_and_det(xy, tri, u)[0]


def _gradients_and_det(xy, tri, u):
    """The triangles' P1 gradients of u (T, 2) and the determinants of their edge vectors (T,)."""
    p0, p1, p2 = xy[tri[:, 0]], xy[tri[:, 1]], xy[tri[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    d1, d2 = u[tri[:, 1]] - u[tri[:, 0]], u[tri[:, 2]] - u[tri[:, 0]]
    g = np.column_stack([(d1 * e2[:, 1] - d2 * e1[:, 1]) / det, (-d1 * e2[:, 0] + d2 * e1[:, 0]) / det])
    return g, det


def _item(h5name, dims, kind, path):
    d = " ".join(str(v) for v in dims)
    return (f'<DataItem Dimensions="{d}" NumberType="{kind}" Precision="8" Format="HDF">'
            f"{h5name}:{path}</DataItem>")


def _attribute(h5name, name, n, path, values, center="Node"):
    vector = values.ndim == 2
    dims = (n, 3) if vector else (n,)
    kind = "Vector" if vector else "Scalar"
    return (f'<Attribute Name="{name}" AttributeType="{kind}" Center="{center}">'
            f"{_item(h5name, dims, 'Float', path)}</Attribute>")


def _grid(h5name, grid, topology, cells, cells_path, n, points_path, fields, fields_path, cell_fields=None):
    """One XDMF <Grid> named `grid`: `cells` (count, nodes per cell) of `topology` at the HDF5 path
    cells_path, n points (3 coordinates) at points_path, one node-centred attribute per entry of
    `fields` and one cell-centred attribute per entry of `cell_fields`, at fields_path/<key>."""
    parts = [f'<Grid Name="{grid}" GridType="Uniform">',
             f'<Topology TopologyType="{topology}" NumberOfElements="{cells[0]}" NodesPerElement="{cells[1]}">'
             f"{_item(h5name, cells, 'Int', cells_path)}</Topology>",
             f'<Geometry GeometryType="XYZ">{_item(h5name, (n, 3), "Float", points_path)}</Geometry>']
    for key, values in fields.items():
        parts.append(_attribute(h5name, key, n, f"{fields_path}/{key}", np.asarray(values)))
    for key, values in (cell_fields or {}).items():
        parts.append(_attribute(h5name, key, cells[0], f"{fields_path}/{key}", np.asarray(values), "Cell"))
    return "\n".join(parts + ["</Grid>"])


def _mesh_grid(h5name, level, fs):
    """The grid of a level's mesh (triangles) with its point fields."""
    name = f"level{level}"
    return _grid(h5name, name, "Triangle", (len(fs["tri"]), 3), f"/meshes/{name}/triangles",
                 len(fs["xy"]), f"/meshes/{name}/points", fs["point"], f"/cases/{name}", fs.get("cell"))


def _segments(fs):
    """(S, 2) the crack segments of a field set: its "segments", else consecutive rows (one crack)."""
    if fs.get("segments") is not None:
        return np.asarray(fs["segments"], dtype=np.int64).reshape(-1, 2)
    m = len(fs["crack"])
    return np.column_stack([np.arange(m - 1), np.arange(1, m)]).astype(np.int64)


def _crack_grid(h5name, level, fs):
    """The grid of a level's crack (segments) with its crack fields."""
    name = f"level{level}"
    return _grid(h5name, f"{name}/crack", "Polyline", (len(_segments(fs)), 2),
                 f"/cases/{name}/crack/segments", len(fs["crack"]), f"/cases/{name}/crack/points",
                 fs["crack_fields"], f"/cases/{name}/crack")


def _pad3(a):
    a = np.asarray(a, dtype=float)
    return np.column_stack([a, np.zeros(len(a))]) if a.ndim == 2 and a.shape[1] == 2 else a


def write_fields(folder, field_sets, tool):
    """Writes the files into `folder` (the caller's temporary output folder); `tool` ("dolfinx",
    "freefem") goes into the HDF5 attributes.

    field_sets: [(level, {"xy": (N,2), "tri": (T,3), "crack": (I,2) (+, −) vertex pairs (crack.txt),
                          "segments": (S,2) row pairs within each crack (optional: absent, the
                          rows form one crack), "point": {name: (N,) or (N,2)},
                          "cell": {name: (T,) or (T,3)} (optional: per triangle, e.g. the elastic
                          references' stress (σ_xx, σ_yy, σ_xy); Center="Cell" in the XDMF),
                          "crack_fields": {name: (I,)}, "h": mesh size (optional)})]."""
    import h5py

    head = '<?xml version="1.0"?>\n<Xdmf Version="3.0">\n<Domain>\n'
    tail = "</Domain>\n</Xdmf>\n"
    (folder / "fields").mkdir()
    with h5py.File(folder / "fields.h5", "w") as h5:
        h5.attrs["tool"] = str(tool)
        for level, fs in field_sets:
            name = f"level{level}"
            attrs = {"level": int(level), "tool": str(tool)}
            if fs.get("h") is not None:
                attrs["h"] = float(fs["h"])

            def put(path, values):
                h5[path] = values
                h5[path].attrs.update(attrs)

            fs = dict(fs, point={k: _pad3(v) for k, v in fs["point"].items()})
            put(f"/meshes/{name}/points", _pad3(fs["xy"]))
            put(f"/meshes/{name}/triangles", np.asarray(fs["tri"], dtype=np.int64))
            for key, values in fs["point"].items():
                put(f"/cases/{name}/{key}", values)
            for key, values in (fs.get("cell") or {}).items():
                put(f"/cases/{name}/{key}", np.asarray(values, dtype=float))
            crack = np.asarray(fs["crack"])
            put(f"/cases/{name}/crack/points", _pad3(np.asarray(fs["xy"])[crack[:, 0]]))
            put(f"/cases/{name}/crack/segments", _segments(fs))
            for key, values in fs["crack_fields"].items():
                put(f"/cases/{name}/crack/{key}", np.asarray(values, dtype=float))
            (folder / "fields" / f"{name}.xdmf").write_text(head + _mesh_grid("../fields.h5", level, fs) + "\n" + tail)
            (folder / "fields" / f"{name}.crack.xdmf").write_text(
                head + _crack_grid("../fields.h5", level, fs) + "\n" + tail)
