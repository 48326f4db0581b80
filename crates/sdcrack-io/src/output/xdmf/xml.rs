//! The XDMF 3 text of the field files: documents, temporal collections, step grids, their
//! `DataItem`s pointing into the HDF5 file, and attributes (the layout is described in the
//! parent module). Pure text: nothing here touches a file.

use super::data::{CaseFields, Centering, Field, GridPart, MeshData, Meta};

fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(ch),
        }
    }
    out
}

pub(super) fn document(domain_body: &str) -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n\
         <Xdmf Version=\"3.0\">\n  <Domain>\n{domain_body}  </Domain>\n</Xdmf>\n"
    )
}

/// A `DataItem` pointing at `h5:path`; `dims` are the dataset dimensions.
fn data_item(indent: &str, h5: &str, h5_path: &str, dims: &[usize], int: bool) -> String {
    let dims: Vec<String> = dims.iter().map(|d| d.to_string()).collect();
    let ty = if int { "Int" } else { "Float" };
    format!(
        "{indent}<DataItem Dimensions=\"{}\" DataType=\"{ty}\" Precision=\"8\" Format=\"HDF\">{}:{}</DataItem>\n",
        dims.join(" "),
        xml_escape(h5),
        xml_escape(h5_path)
    )
}

fn attribute(indent: &str, name: &str, kind: &str, center: &str, item: String) -> String {
    format!(
        "{indent}<Attribute Name=\"{name}\" AttributeType=\"{kind}\" Center=\"{center}\">\n{item}{indent}</Attribute>\n"
    )
}

/// A temporal collection named `name` around the step grids `body`.
pub(super) fn temporal(name: &str, body: &str) -> String {
    format!(
        "    <Grid Name=\"{}\" GridType=\"Collection\" CollectionType=\"Temporal\">\n{body}    </Grid>\n",
        xml_escape(name)
    )
}

/// Opening of the grid `name`. As step `k` of a series: its `Time` and its metadata as
/// `Information`. As a one-state file (`k` None): neither, since `meshio.read` rejects both (it
/// reads `Information` only in its own format); the metadata stay in the HDF5 attributes.
fn step_head(name: &str, k: Option<usize>, metadata: &[(String, Meta)], indent: &str) -> String {
    let mut s = format!(
        "{indent}<Grid Name=\"{}\" GridType=\"Uniform\">\n",
        xml_escape(name)
    );
    let Some(k) = k else { return s };
    s.push_str(&format!("{indent}  <Time Value=\"{k}\"/>\n"));
    for (key, value) in metadata {
        s.push_str(&format!(
            "{indent}  <Information Name=\"{}\" Value=\"{}\"/>\n",
            xml_escape(key),
            xml_escape(&value.to_string())
        ));
    }
    s
}

/// The node attributes of `case.constants`, stored under `group` with `n` values each.
fn constant_attributes(indent: &str, h5: &str, group: &str, n: usize, case: &CaseFields) -> String {
    let inner = format!("{indent}  ");
    case.constants
        .iter()
        .map(|(name, _)| {
            let item = data_item(&inner, h5, &format!("{group}/{name}"), &[n], false);
            attribute(indent, &xml_escape(name), "Scalar", "Node", item)
        })
        .collect()
}

/// The attributes of `case`'s further fields on `part` ([`CaseFields::extra`]), stored under
/// `group`.
fn extra_attributes(
    indent: &str,
    inner: &str,
    h5: &str,
    group: &str,
    case: &CaseFields,
    part: GridPart,
) -> String {
    (case.extra.iter().filter(|f| f.part == part))
        .map(|f: &Field| {
            let c = f.kind.components();
            let n = f.values.len() / c;
            let dims = if c == 1 { vec![n] } else { vec![n, c] };
            let item = data_item(inner, h5, &format!("{group}/{}", f.name), &dims, false);
            let center = match f.center {
                Centering::Node => "Node",
                Centering::Cell => "Cell",
            };
            attribute(indent, &xml_escape(&f.name), f.kind.xdmf(), center, item)
        })
        .collect()
}

/// The cells of a grid: XDMF topology type, number of cells, nodes per cell, and the HDF5 path
/// of their node indices.
struct Cells {
    topology: &'static str,
    count: usize,
    nodes_per_cell: usize,
    connectivity: String,
}

/// A grid's `Topology` (its `cells`) and `Geometry` (the `n` XYZ points at `points` of `h5`),
/// inside a grid opened at `indent`.
fn topology_geometry(indent: &str, h5: &str, cells: &Cells, points: &str, n: usize) -> String {
    let (i2, i3) = (format!("{indent}  "), format!("{indent}    "));
    let Cells {
        topology,
        count,
        nodes_per_cell,
        connectivity,
    } = cells;
    let mut s = format!(
        "{i2}<Topology TopologyType=\"{topology}\" NumberOfElements=\"{count}\" NodesPerElement=\"{nodes_per_cell}\">\n"
    );
    s.push_str(&data_item(
        &i3,
        h5,
        connectivity,
        &[*count, *nodes_per_cell],
        true,
    ));
    s.push_str(&format!(
        "{i2}</Topology>\n{i2}<Geometry GeometryType=\"XYZ\">\n"
    ));
    s.push_str(&data_item(&i3, h5, points, &[n, 3], false));
    s.push_str(&format!("{i2}</Geometry>\n"));
    s
}

/// Where one grid of a case stands in the file: its name, its step `k` of a series or (None) a
/// one-state grid, its cells, the HDF5 path of its `n` points, and the group holding its constant
/// attributes.
struct GridSpec<'a> {
    name: &'a str,
    k: Option<usize>,
    cells: Cells,
    points: String,
    n: usize,
    constants: &'a str,
}

/// One grid of `case` opened at `indent`: head, topology and geometry, the field attributes
/// `fields` writes (given the attribute indent and the data-item indent), the constant
/// attributes, and the closing tag.
fn grid_xml(
    h5: &str,
    case: &CaseFields,
    spec: GridSpec,
    indent: &str,
    fields: impl FnOnce(&str, &str) -> String,
) -> String {
    let (i2, i3) = (format!("{indent}  "), format!("{indent}    "));
    let mut s = step_head(spec.name, spec.k, &case.metadata, indent);
    s.push_str(&topology_geometry(
        indent,
        h5,
        &spec.cells,
        &spec.points,
        spec.n,
    ));
    s.push_str(&fields(&i2, &i3));
    s.push_str(&constant_attributes(&i2, h5, spec.constants, spec.n, case));
    s.push_str(&format!("{indent}</Grid>\n"));
    s
}

/// The triangle grid of `case`, step `k` of its series or (None) a one-state grid.
pub(super) fn mesh_grid_xml(
    h5: &str,
    mesh: &MeshData,
    case: &CaseFields,
    k: Option<usize>,
    indent: &str,
) -> String {
    let mp = format!("/meshes/{}", mesh.key);
    let cp = format!("/cases/{}", case.name);
    let n = mesh.points.len();
    let spec = GridSpec {
        name: &case.name,
        k,
        cells: Cells {
            topology: "Triangle",
            count: mesh.triangles.len(),
            nodes_per_cell: 3,
            connectivity: format!("{mp}/triangles"),
        },
        points: format!("{mp}/points"),
        n,
        constants: &cp,
    };
    grid_xml(h5, case, spec, indent, |i2, i3| {
        let mut s = String::new();
        if case.u.is_some() {
            let item = data_item(i3, h5, &format!("{cp}/u"), &[n], false);
            s.push_str(&attribute(i2, "u", "Scalar", "Node", item));
        }
        if case.p.is_some() {
            let item = data_item(i3, h5, &format!("{cp}/p"), &[n, 3], false);
            s.push_str(&attribute(i2, "p", "Vector", "Node", item));
        }
        s.push_str(&extra_attributes(i2, i3, h5, &cp, case, GridPart::Mesh));
        s
    })
}

/// The crack polylines of `case`, step `k` of its series or (None) a one-state grid.
pub(super) fn crack_grid_xml(
    h5: &str,
    case: &CaseFields,
    k: Option<usize>,
    indent: &str,
) -> String {
    let kp = format!("/cases/{}/crack", case.name);
    let n = case.crack_points.len();
    let name = format!("{}/crack", case.name);
    let spec = GridSpec {
        name: &name,
        k,
        cells: Cells {
            topology: "Polyline",
            count: case.crack_segments.len(),
            nodes_per_cell: 2,
            connectivity: format!("{kp}/segments"),
        },
        points: format!("{kp}/points"),
        n,
        constants: &kp,
    };
    grid_xml(h5, case, spec, indent, |i2, i3| {
        let mut s = String::new();
        if let Some((centering, lambda)) = &case.lambda {
            let center = match centering {
                Centering::Node => "Node",
                Centering::Cell => "Cell",
            };
            let item = data_item(i3, h5, &format!("{kp}/lambda"), &[lambda.len()], false);
            s.push_str(&attribute(i2, "lambda", "Scalar", center, item));
        }
        if case.jump.is_some() {
            let item = data_item(i3, h5, &format!("{kp}/jump"), &[n], false);
            s.push_str(&attribute(i2, "jump", "Scalar", "Node", item));
        }
        s.push_str(&extra_attributes(i2, i3, h5, &kp, case, GridPart::Crack));
        s
    })
}
