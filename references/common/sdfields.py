"""Field files of the reference solvers: fields.h5 + fields.xdmf in the layout of the solver's
writer (src/output/xdmf.rs), one grid per level on the cracked mesh, so ParaView and the compare
tool read solver and references alike.

    fields.h5   /meshes/level{L}/points (N,3)   /meshes/level{L}/triangles (T,3) int64
                /cases/level{L}/<point field>   scalar (N,) or vector (N,3)
                /cases/level{L}/crack/points (I+1,3)  /crack/segments (I,2)  /crack/<crack field> (I+1,)
    fields.xdmf a spatial collection of the grids "level{L}" and "level{L}/crack"
    fields/level{L}.xdmf, fields/level{L}.crack.xdmf   one grid each (meshio reads one grid a file)
"""

import numpy as np


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


def _mesh_grid(h5name, level, fs):
    name, n, nt = f"level{level}", len(fs["xy"]), len(fs["tri"])
    parts = [f'<Grid Name="{name}" GridType="Uniform">',
             f'<Topology TopologyType="Triangle" NumberOfElements="{nt}" NodesPerElement="3">'
             f"{_item(h5name, (nt, 3), 'Int', f'/meshes/{name}/triangles')}</Topology>",
             f'<Geometry GeometryType="XYZ">{_item(h5name, (n, 3), "Float", f"/meshes/{name}/points")}</Geometry>']
    for key, values in fs["point"].items():
        parts.append(_attribute(h5name, key, n, f"/cases/{name}/{key}", np.asarray(values)))
    return "\n".join(parts + ["</Grid>"])


def _crack_grid(h5name, level, fs):
    name, m = f"level{level}", len(fs["crack"])
    parts = [f'<Grid Name="{name}/crack" GridType="Uniform">',
             f'<Topology TopologyType="Polyline" NumberOfElements="{m - 1}" NodesPerElement="2">'
             f"{_item(h5name, (m - 1, 2), 'Int', f'/cases/{name}/crack/segments')}</Topology>",
             f'<Geometry GeometryType="XYZ">{_item(h5name, (m, 3), "Float", f"/cases/{name}/crack/points")}</Geometry>']
    for key, values in fs["crack_fields"].items():
        parts.append(_attribute(h5name, key, m, f"/cases/{name}/crack/{key}", np.asarray(values)))
    return "\n".join(parts + ["</Grid>"])


def _pad3(a):
    a = np.asarray(a, dtype=float)
    return np.column_stack([a, np.zeros(len(a))]) if a.ndim == 2 and a.shape[1] == 2 else a


def write_fields(folder, field_sets):
    """Writes the files into `folder` (the caller's temporary output folder).

    field_sets: [(level, {"xy": (N,2), "tri": (T,3), "crack": (I+1,2) (+, −) vertex pairs,
                          "point": {name: (N,) or (N,2)}, "crack_fields": {name: (I+1,)}})]."""
    import h5py

    head = '<?xml version="1.0"?>\n<Xdmf Version="3.0">\n<Domain>\n'
    tail = "</Domain>\n</Xdmf>\n"
    (folder / "fields").mkdir()
    grids = []
    with h5py.File(folder / "fields.h5", "w") as h5:
        for level, fs in field_sets:
            name = f"level{level}"
            fs = dict(fs, point={k: _pad3(v) for k, v in fs["point"].items()})
            h5[f"/meshes/{name}/points"] = _pad3(fs["xy"])
            h5[f"/meshes/{name}/triangles"] = np.asarray(fs["tri"], dtype=np.int64)
            for key, values in fs["point"].items():
                h5[f"/cases/{name}/{key}"] = values
            crack = np.asarray(fs["crack"])
            h5[f"/cases/{name}/crack/points"] = _pad3(np.asarray(fs["xy"])[crack[:, 0]])
            m = len(crack)
            h5[f"/cases/{name}/crack/segments"] = np.column_stack(
                [np.arange(m - 1), np.arange(1, m)]).astype(np.int64)
            for key, values in fs["crack_fields"].items():
                h5[f"/cases/{name}/crack/{key}"] = np.asarray(values, dtype=float)
            grids += [_mesh_grid("fields.h5", level, fs), _crack_grid("fields.h5", level, fs)]
            (folder / "fields" / f"{name}.xdmf").write_text(head + _mesh_grid("../fields.h5", level, fs) + "\n" + tail)
            (folder / "fields" / f"{name}.crack.xdmf").write_text(
                head + _crack_grid("../fields.h5", level, fs) + "\n" + tail)
    (folder / "fields.xdmf").write_text(
        head + '<Grid Name="fields" GridType="Collection" CollectionType="Spatial">\n'
        + "\n".join(grids) + "\n</Grid>\n" + tail)
