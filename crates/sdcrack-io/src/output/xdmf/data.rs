//! What the field files hold: the meshes, each case's fields and their metadata, as the writer
//! and the XDMF text read them.

/// A triangle mesh, shared by all cases whose `mesh_key` equals its `key`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshData {
    /// Identifier referenced by [`CaseFields::mesh_key`]; also the HDF5 group name under `/meshes`.
    pub key: String,
    /// Node coordinates (written with z = 0).
    pub points: Vec<[f64; 2]>,
    /// Triangles as 0-based node indices.
    pub triangles: Vec<[usize; 3]>,
}

/// Where a crack field lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Centering {
    /// One value per crack node (`I + 1` values).
    Node,
    /// One value per crack segment (`I` values).
    Cell,
}

/// The fields of one solved case.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseFields {
    /// Grid name (unique); also HDF5 group name under `/cases` and per-case file name.
    pub name: String,
    /// Key of the [`MeshData`] the point fields live on.
    pub mesh_key: String,
    /// Displacement, one value per mesh node.
    pub u: Option<Vec<f64>>,
    /// Flux / gradient variable, one 2-vector per mesh node (written with z = 0).
    pub p: Option<Vec<[f64; 2]>>,
    /// Bubble coefficients of p, one 2-vector per mesh triangle (same order as the triangles):
    /// on triangle T, p_h = Σ_i p_i λ_i + p_bubble\[T\] · 27 λ0 λ1 λ2 (the MINI field). Only with `p`.
    pub p_bubble: Option<Vec<[f64; 2]>>,
    /// Crack nodes (every crack's, concatenated; empty for no crack grid).
    pub crack_points: Vec<[f64; 2]>,
    /// Crack segments as pairs of indices into `crack_points` (within one crack; `I` of them).
    pub crack_segments: Vec<[usize; 2]>,
    /// The multiplier λ_h of the smooth-domain method on the crack, per node or per segment
    /// (it approximates the jump [u]).
    pub lambda: Option<(Centering, Vec<f64>)>,
    /// [u_h] = u⁺ − u⁻ of the case's own u at each crack node (`crack_points`' order), + the face
    /// the crack normal ν (the segment direction turned by +90°) points into: the references'
    /// `jump`. Zero at the tips and, for the continuous u space, everywhere.
    pub jump: Option<Vec<f64>>,
    /// Name of the series the case is a step of (see the module documentation): the cases of
    /// one series share one mesh and one crack, and are its steps in the order given.
    pub series: String,
    /// Named values describing the case (the solver's: level, h, u space, multiplier, δ),
    /// written as HDF5 attributes and XDMF `Information` elements.
    pub metadata: Vec<(String, Meta)>,
    /// Values also written as constant point fields of the mesh and crack grids (the solver's:
    /// `delta`), so that a viewer that ignores `Information` (ParaView) shows them per step.
    pub constants: Vec<(String, f64)>,
    /// Further fields of any shape on the mesh or the crack grid (the elastic cases' σ, u*,
    /// u_h, γ_h, opening, …): empty for the scalar problem's cases.
    pub extra: Vec<Field>,
}

/// Which grid of a case a [`Field`] lives on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridPart {
    /// The triangle mesh (`/cases/CASE/NAME`).
    Mesh,
    /// The crack polylines (`/cases/CASE/crack/NAME`).
    Crack,
}

/// The XDMF attribute type of a [`Field`] and its components per value: a scalar (1), a vector
/// written in 3-D (3: x, y, 0) or a tensor written in 3-D (9: row-major 3 × 3, the z row and
/// column 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// One component.
    Scalar,
    /// Three components (x, y, z).
    Vector,
    /// Nine components, row-major 3 × 3.
    Tensor,
}

impl FieldKind {
    /// Components per value.
    pub fn components(self) -> usize {
        match self {
            FieldKind::Scalar => 1,
            FieldKind::Vector => 3,
            FieldKind::Tensor => 9,
        }
    }

    /// XDMF's `AttributeType`.
    pub fn xdmf(self) -> &'static str {
        match self {
            FieldKind::Scalar => "Scalar",
            FieldKind::Vector => "Vector",
            FieldKind::Tensor => "Tensor",
        }
    }
}

/// A field of a case beyond u, p and λ: its name (an HDF5 dataset and an XDMF attribute), its
/// grid, centering and kind, and its values (per node or cell of its grid, each
/// [`FieldKind::components`] numbers, flattened).
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Dataset and attribute name.
    pub name: String,
    /// The grid it lives on.
    pub part: GridPart,
    /// Per node or per cell of that grid.
    pub center: Centering,
    /// Its attribute type.
    pub kind: FieldKind,
    /// The values, flattened.
    pub values: Vec<f64>,
}
/// A metadata value of a case.
#[derive(Clone, Debug, PartialEq)]
pub enum Meta {
    /// An integer.
    Int(i64),
    /// A number, written in XDMF as its shortest round-trip form (`0.01` as `1e-2`, zero as `0`).
    Float(f64),
    /// A text.
    Text(String),
}

impl From<sdcrack_core::case::AxisValue> for Meta {
    /// A case axis' value as its group's attribute.
    fn from(v: sdcrack_core::case::AxisValue) -> Meta {
        use sdcrack_core::case::AxisValue;
        match v {
            AxisValue::Int(i) => Meta::Int(i64::from(i)),
            AxisValue::Number(x) => Meta::Float(x),
            AxisValue::Name(n) => Meta::Text(n.to_string()),
        }
    }
}

impl std::fmt::Display for Meta {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Meta::Int(i) => write!(f, "{i}"),
            Meta::Float(x) if *x == 0.0 => write!(f, "0"),
            Meta::Float(x) => write!(f, "{x:e}"),
            Meta::Text(t) => f.write_str(t),
        }
    }
}
