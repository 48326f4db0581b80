//! Assembly of the condensed discrete system of paper eq. (15) and of the crack operators.
//!
//! Unknowns: x = [P; U], P the vertex values of p (2 per vertex, interleaved (p_x, p_y)), U the u
//! dofs of the chosen u space. With the bubbles condensed (see [`crate::fe::mini`]) the system is
//!
//! ```text
//! [ G̃   B̃ᵀ          ] [P]   [G_Γ − Dᵀμ]      G_Γ = ∫_Γ g (q·n) ds,
//! [ B̃   −(δM + C)   ] [U] = [   −F    ]      F   = ∫_Ω f v dx,  C = 7/10 · P1 stiffness,
//! ```
//!
//! symmetric quasi-definite for δ > 0 and nonsingular at δ = 0. With the broken-tangential p
//! space ([`crate::mesh::PTopology`]) the p unknowns of a corner at a doubled crack vertex are
//! written in the frame (ν, τ): the element's p rows and columns are transformed by the corner's
//! rotation R = [ν τ] (K_T ← Tᵀ K_T T, T = diag(R_0, R_1, R_2, I₃)), which is the same element
//! integrals of (15) for the basis functions λ_k ν, λ_k τ; the + and − faces' corners share the
//! p·ν unknown and each has its own p·τ. The matrix is stored once as a
//! lower-triangular CSC pattern with two value arrays — the δ-independent part and the part
//! multiplying δ — so that K(δ) is one axpy and its symbolic factorisation is shared by every δ.
//!
//! The crack operators N and D = S N of the multipliers live in [`crate::multiplier`].

use rayon::prelude::*;
use std::ops::Range;

use crate::expr::Expr;
use crate::fe::mini::{condensed_element, CondensedElement};
use crate::fe::p1::TriangleGeometry;
use crate::fe::quadrature::{gauss_legendre, physical_points, triangle_rule, REFERENCE_TRIANGLE};
use crate::linalg::SymCsc;
use crate::mesh::{Mesh, PCorner, PTopology, UTopology};
use crate::problem::PMass;

/// Errors while assembling.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AssemblyError {
    /// Data evaluated to NaN or ±inf at a quadrature point.
    #[error(
        "data.{name} = \"{source_text}\" evaluates to {value} at the quadrature point ({x}, {y})"
    )]
    NonFinite {
        /// `f` or `g`.
        name: &'static str,
        /// The expression.
        source_text: String,
        /// The offending value.
        value: f64,
        /// x of the point.
        x: f64,
        /// y of the point.
        y: f64,
    },
}

/// The condensed linear system of one mesh and u space, for every δ.
#[derive(Clone, Debug)]
pub struct System {
    /// Number of p unknowns (2 per vertex, plus one per doubled crack vertex).
    pub n_p: usize,
    /// Number of u unknowns.
    pub n_u: usize,
    /// K(0): lower-triangular CSC with the δ-independent values. The study moves it out for its
    /// δ sweep (then this is an empty matrix).
    pub base: SymCsc,
    /// The entries of ∂K/∂δ = −M (the u–u block) that are not zero: their positions in the
    /// pattern of `base`, with K(0)'s and ∂K/∂δ's values there. A sweep writes K(δ) into one
    /// matrix of `base`'s pattern through these ([`System::set_delta`]) instead of holding K(0)
    /// and K(δ) side by side.
    pub delta_entries: Vec<DeltaEntry>,
    /// `‖∂K/∂δ‖₁`.
    pub delta_norm1: f64,
    /// Right-hand side [G_Γ; −F].
    pub rhs: Vec<f64>,
    /// Expected pivot signs: +1 for p rows, −1 for u rows.
    pub signs: Vec<i8>,
}

impl System {
    /// Total number of unknowns.
    pub fn n(&self) -> usize {
        self.n_p + self.n_u
    }

    /// K(δ) = K(0) + δ ∂K/∂δ, a new matrix.
    pub fn matrix(&self, delta: f64) -> SymCsc {
        let mut k = self.base.clone();
        self.set_delta(&mut k, delta);
        k
    }

    /// Overwrites `k`, a matrix with the pattern of `base` holding K(δ') for any δ', with K(δ):
    /// the same values, bit for bit, as [`System::matrix`].
    ///
    /// # Panics
    /// If `k` has fewer entries than `base`'s pattern (caller bug).
    pub fn set_delta(&self, k: &mut SymCsc, delta: f64) {
        for e in &self.delta_entries {
            k.values[e.position] = if delta != 0.0 {
                e.base + delta * e.derivative
            } else {
                e.base
            };
        }
    }

    /// ∂K/∂δ on the pattern of `base` (zeros included).
    pub fn delta_values(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.base.values.len()];
        for e in &self.delta_entries {
            d[e.position] = e.derivative;
        }
        d
    }
}

/// One entry of K whose value depends on δ.
#[derive(Clone, Copy, Debug)]
pub struct DeltaEntry {
    /// Position in the values of K's pattern.
    pub position: usize,
    /// K(0) there.
    pub base: f64,
    /// ∂K/∂δ there (not zero).
    pub derivative: f64,
}

/// Number of Gauss points per direction for the load vector ∫ f v (degree 8 exact).
const LOAD_DEGREE: usize = 8;
/// Gauss points per boundary edge for ∫_Γ g q·n (exact for g of degree ≤ 8).
const BOUNDARY_POINTS: usize = 5;

/// Assembles the condensed system for `mesh`, u space `topo`, p space `ptopo`, data `f` (source)
/// and `g` (Dirichlet), with the p–p block of `p_mass`: G̃, or for [`PMass::Lumped`] its row-sum
/// diagonal D (element by element: the row sums of G̃_T are |T|/3 − 3·7|T|/90 = |T|/10), which
/// leaves B̃, C, M and the right-hand side unchanged. D is a multiple of the identity at each
/// corner, so it stays diagonal in a corner's (ν, τ) frame: the lumped elimination of p stays
/// exact with the broken-tangential p.
pub fn assemble(
    mesh: &Mesh,
    topo: &UTopology,
    ptopo: &PTopology,
    f: &Expr,
    g: &Expr,
    p_mass: PMass,
) -> Result<System, AssemblyError> {
    let n_p = ptopo.n_dofs;
    let n_u = topo.n_dofs;
    let n = n_p + n_u;
    let (base, delta_values) = assemble_matrix(mesh, topo, ptopo, p_mass);
    let delta_norm1 = base.norm1_with(&delta_values);
    let delta_entries = delta_values
        .iter()
        .enumerate()
        .filter(|(_, &d)| d != 0.0)
        .map(|(position, &derivative)| DeltaEntry {
            position,
            base: base.values[position],
            derivative,
        })
        .collect();
    drop(delta_values);
    let mut rhs = vec![0.0; n];
    boundary_term(mesh, g, &mut rhs[..n_p])?;
    let load = load_vector(mesh, topo, f)?;
    for (r, l) in rhs[n_p..].iter_mut().zip(load) {
        *r = -l;
    }
    let mut signs = vec![1i8; n];
    signs[n_p..].fill(-1);
    Ok(System {
        n_p,
        n_u,
        base,
        delta_entries,
        delta_norm1,
        rhs,
        signs,
    })
}

/// The 9 unknowns of a triangle in the condensed system: the two p unknowns of each of its 3
/// corners (local 0..6, as `2k + d`), then its 3 u dofs (local 6..9).
fn element_unknowns(corners: &[PCorner; 3], udofs: &[usize; 3], n_p: usize) -> [usize; 9] {
    let mut e = [0usize; 9];
    for k in 0..3 {
        e[2 * k] = corners[k].dofs[0];
        e[2 * k + 1] = corners[k].dofs[1];
        e[6 + k] = n_p + udofs[k];
    }
    e
}

/// The corners of triangle `t` as the p space sees them.
fn element_corners(mesh: &Mesh, ptopo: &PTopology, t: usize) -> [PCorner; 3] {
    [0, 1, 2].map(|k| ptopo.corner(mesh, t, k))
}

/// R_kᵀ R_l for two corners: exactly the identity when their frames are the same (always for
/// k = l, and for two corners on one straight crack), so that the lumped diagonal stays diagonal
/// bit for bit.
fn frame_product(a: &PCorner, b: &PCorner) -> [[f64; 2]; 2] {
    if a.normal == b.normal {
        return [[1.0, 0.0], [0.0, 1.0]];
    }
    let (ra, rb) = (a.directions(), b.directions());
    [0, 1].map(|i| [0, 1].map(|j| (0..2).map(|d| ra[i][d] * rb[j][d]).sum()))
}

/// The condensed element in its corners' frames: p–p block (6 × 6) and B̃ (3 × 6) transformed,
/// the u–u block unchanged ([`CondensedElement`] holds the (x, y) frame).
#[derive(Clone, Copy, Debug)]
struct FramedElement {
    /// p–p block: G̃[k][l] (R_kᵀ R_l)_{ij} at [2k + i][2l + j].
    pp: [[f64; 6]; 6],
    /// B̃ R: at [i][2k + j], Σ_d B̃[i][2k + d] R_k[j][d].
    b: [[f64; 6]; 3],
}

impl FramedElement {
    fn new(ce: &CondensedElement, corners: &[PCorner; 3]) -> FramedElement {
        let mut pp = [[0.0; 6]; 6];
        for k in 0..3 {
            for l in 0..3 {
                let r = frame_product(&corners[k], &corners[l]);
                for i in 0..2 {
                    for j in 0..2 {
                        pp[2 * k + i][2 * l + j] = ce.g[k][l] * r[i][j];
                    }
                }
            }
        }
        let mut b = [[0.0; 6]; 3];
        for (i, row) in b.iter_mut().enumerate() {
            for (k, corner) in corners.iter().enumerate() {
                let r = corner.directions();
                for j in 0..2 {
                    row[2 * k + j] = if corner.normal.is_none() {
                        ce.b[i][2 * k + j]
                    } else {
                        r[j][0] * ce.b[i][2 * k] + r[j][1] * ce.b[i][2 * k + 1]
                    };
                }
            }
        }
        FramedElement { pp, b }
    }
}

/// A table of local couplings (a, b) filled in a const context: `pairs[..len]` so far. The
/// order of a table is the order in which the element's values are scattered into K.
struct PairTable<const N: usize> {
    pairs: [(usize, usize); N],
    len: usize,
}

impl<const N: usize> PairTable<N> {
    const fn new() -> Self {
        PairTable {
            pairs: [(0, 0); N],
            len: 0,
        }
    }

    /// Appends the pair (a, b).
    const fn push(mut self, a: usize, b: usize) -> Self {
        self.pairs[self.len] = (a, b);
        self.len += 1;
        self
    }

    /// Appends every pair of the block `rows × cols`, row by row.
    const fn block(mut self, rows: Range<usize>, cols: Range<usize>) -> Self {
        let mut a = rows.start;
        while a < rows.end {
            let mut b = cols.start;
            while b < cols.end {
                self = self.push(a, b);
                b += 1;
            }
            a += 1;
        }
        self
    }

    /// The filled table; it must be full.
    const fn finish(self) -> [(usize, usize); N] {
        assert!(self.len == N, "a pair table must be filled exactly");
        self.pairs
    }
}

/// The local unknowns of u (the p unknowns 0..6 come first): the rows that couple with all 9.
const U_ROWS: Range<usize> = 6..9;

/// Local couplings (a, b) of the condensed element matrix: p–p within one component (G is the
/// scalar matrix times I₂: 18 pairs), then every u row with all 9 unknowns (B̃ and −0.7A − δM:
/// 27 pairs). u unknowns are numbered after p, so these hold every entry of the lower triangle.
const ELEMENT_PAIRS: [(usize, usize); 45] = {
    let mut table = PairTable::new();
    let mut k = 0;
    while k < 3 {
        let mut l = 0;
        while l < 3 {
            table = table.push(2 * k, 2 * l).push(2 * k + 1, 2 * l + 1);
            l += 1;
        }
        k += 1;
    }
    table.block(U_ROWS, 0..9).finish()
};

/// The (K(0), ∂K/∂δ) values of a local pair (a, b) of the condensed element, in the (x, y)
/// frame or, for a triangle at a doubled crack vertex, in its corners' frames.
fn element_value(
    ce: &CondensedElement,
    framed: Option<&FramedElement>,
    a: usize,
    b: usize,
) -> (f64, f64) {
    match (framed, a >= 6, b >= 6) {
        (_, true, true) => (-ce.c[a - 6][b - 6], -ce.m[a - 6][b - 6]),
        (None, false, false) => (ce.g[a / 2][b / 2], 0.0),
        (None, true, false) => (ce.b[a - 6][b], 0.0),
        (None, false, true) => (ce.b[b - 6][a], 0.0),
        (Some(fe), false, false) => (fe.pp[a][b], 0.0),
        (Some(fe), true, false) => (fe.b[a - 6][b], 0.0),
        (Some(fe), false, true) => (fe.b[b - 6][a], 0.0),
    }
}

/// Assembles K(0) and ∂K/∂δ (same pattern, lower triangle) element by element: the pattern
/// from the element couplings, then the condensed element values scattered into it.
fn assemble_matrix(
    mesh: &Mesh,
    topo: &UTopology,
    ptopo: &PTopology,
    p_mass: PMass,
) -> (SymCsc, Vec<f64>) {
    let n_p = ptopo.n_dofs;
    let n = n_p + topo.n_dofs;
    let (col_ptr, row_idx) = lower_pattern(n, mesh, topo, ptopo, p_mass);
    let mut values = vec![0.0; row_idx.len()];
    let mut dvals = vec![0.0; row_idx.len()];
    // element matrices in parallel, a chunk at a time (bounded memory), scattered sequentially
    const CHUNK: usize = 1 << 15;
    let triangles = mesh
        .triangles
        .chunks(CHUNK)
        .zip(topo.triangle_dofs.chunks(CHUNK))
        .enumerate();
    for (chunk, (tris, dofs)) in triangles {
        let elements: Vec<CondensedElement> = tris
            .par_iter()
            .map(|t| {
                let ce = condensed_element(&TriangleGeometry::new(t.map(|v| mesh.vertices[v])));
                match p_mass {
                    PMass::Consistent => ce,
                    PMass::Lumped => ce.lumped(),
                }
            })
            .collect();
        for (i, (udofs, ce)) in dofs.iter().zip(&elements).enumerate() {
            let t = chunk * CHUNK + i;
            let corners = element_corners(mesh, ptopo, t);
            let framed = ptopo
                .has_frame(mesh, t)
                .then(|| FramedElement::new(ce, &corners));
            let e = element_unknowns(&corners, udofs, n_p);
            for &(a, b) in element_pairs(p_mass, framed.is_some()) {
                let (r, c) = (e[a], e[b]);
                if r < c {
                    continue;
                }
                let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
                let pos = col_ptr[c]
                    + rows
                        .binary_search(&r)
                        .unwrap_or_else(|_| unreachable!("({r}, {c}) is in the pattern"));
                let (v, d) = element_value(ce, framed.as_ref(), a, b);
                values[pos] += v;
                dvals[pos] += d;
            }
        }
    }
    let base = SymCsc {
        n,
        col_ptr,
        row_idx,
        values,
    };
    (base, dvals)
}

/// The local couplings of an element: all of [`ELEMENT_PAIRS`], or for the lumped p mass those
/// without the off-diagonal p–p pairs (zero there, and left out of the pattern: a structural
/// p–p coupling would make the p-first elimination of the lumped order fill the p block). A
/// `framed` element (a corner at a doubled crack vertex) with the consistent mass couples the
/// two components of different corners as well ([`FRAMED_ELEMENT_PAIRS`]); with the lumped mass
/// its p–p block is still the diagonal (R_kᵀ R_k = I).
fn element_pairs(p_mass: PMass, framed: bool) -> &'static [(usize, usize)] {
    match (p_mass, framed) {
        (PMass::Consistent, false) => &ELEMENT_PAIRS,
        (PMass::Consistent, true) => &FRAMED_ELEMENT_PAIRS,
        (PMass::Lumped, _) => &LUMPED_ELEMENT_PAIRS,
    }
}

/// Every p–p pair (36), then the 27 u rows: the couplings of a framed element.
const FRAMED_ELEMENT_PAIRS: [(usize, usize); 63] = PairTable::new()
    .block(0..6, 0..6)
    .block(U_ROWS, 0..9)
    .finish();

/// [`ELEMENT_PAIRS`] without the off-diagonal p–p pairs (6 diagonal p pairs, then the 27 u rows).
const LUMPED_ELEMENT_PAIRS: [(usize, usize); 33] = {
    let mut table = PairTable::new();
    let mut k = 0;
    while k < ELEMENT_PAIRS.len() {
        let (a, b) = ELEMENT_PAIRS[k];
        if a >= 6 || b >= 6 || a == b {
            table = table.push(a, b);
        }
        k += 1;
    }
    table.finish()
};

/// Column pointers and sorted row indices of the lower triangle coupled by the elements.
fn lower_pattern(
    n: usize,
    mesh: &Mesh,
    topo: &UTopology,
    ptopo: &PTopology,
    p_mass: PMass,
) -> (Vec<usize>, Vec<usize>) {
    let n_p = ptopo.n_dofs;
    let lower_pairs = |t: usize, udofs: &[usize; 3]| {
        let e = element_unknowns(&element_corners(mesh, ptopo, t), udofs, n_p);
        element_pairs(p_mass, ptopo.has_frame(mesh, t))
            .iter()
            .map(move |&(a, b)| (e[a], e[b]))
            .filter(|(r, c)| r >= c)
    };
    let mut count = vec![0usize; n + 1];
    for (t, udofs) in topo.triangle_dofs.iter().enumerate() {
        for (_, c) in lower_pairs(t, udofs) {
            count[c + 1] += 1;
        }
    }
    for c in 0..n {
        count[c + 1] += count[c];
    }
    let mut next = count.clone();
    let mut rows = vec![0usize; count[n]];
    for (t, udofs) in topo.triangle_dofs.iter().enumerate() {
        for (r, c) in lower_pairs(t, udofs) {
            rows[next[c]] = r;
            next[c] += 1;
        }
    }
    // sort and deduplicate each column, compacting in place
    let mut col_ptr = vec![0usize; n + 1];
    let mut write = 0;
    for c in 0..n {
        let column = &mut rows[count[c]..count[c + 1]];
        column.sort_unstable();
        let mut last = usize::MAX;
        for k in count[c]..count[c + 1] {
            let r = rows[k];
            if r != last {
                rows[write] = r;
                write += 1;
                last = r;
            }
        }
        col_ptr[c + 1] = write;
    }
    rows.truncate(write);
    rows.shrink_to_fit();
    (col_ptr, rows)
}

fn non_finite(name: &'static str, e: &Expr, value: f64, p: [f64; 2]) -> AssemblyError {
    AssemblyError::NonFinite {
        name,
        source_text: e.source().to_string(),
        value,
        x: p[0],
        y: p[1],
    }
}

/// G_Γ: ∫_Γ g λ_k n_d ds into the p rows (bubbles vanish on Γ).
fn boundary_term(mesh: &Mesh, g: &Expr, out: &mut [f64]) -> Result<(), AssemblyError> {
    let rule = gauss_legendre(BOUNDARY_POINTS);
    for e in &mesh.boundary_edges {
        let [a, b] = e.map(|v| mesh.vertices[v]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy);
        let normal = [dy / len, -dx / len];
        for (&s, &w) in rule.points.iter().zip(&rule.weights) {
            let p = [a[0] + s * dx, a[1] + s * dy];
            let gv = g.eval(p[0], p[1]);
            if !gv.is_finite() {
                return Err(non_finite("g", g, gv, p));
            }
            for (k, phi) in [(e[0], 1.0 - s), (e[1], s)] {
                for d in 0..2 {
                    out[2 * k + d] += w * len * gv * phi * normal[d];
                }
            }
        }
    }
    Ok(())
}

/// F_i = ∫ f φ_i over every triangle (f evaluated only at interior points).
fn load_vector(mesh: &Mesh, topo: &UTopology, f: &Expr) -> Result<Vec<f64>, AssemblyError> {
    let mut load = vec![0.0; topo.n_dofs];
    if f.is_constant() && f.eval(0.0, 0.0) == 0.0 {
        return Ok(load);
    }
    let rule = triangle_rule(LOAD_DEGREE);
    let local: Result<Vec<[f64; 3]>, AssemblyError> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
            let mut r = [0.0; 3];
            for q in physical_points(&rule, geo.vertices, REFERENCE_TRIANGLE) {
                let fv = f.eval(q.x[0], q.x[1]);
                if !fv.is_finite() {
                    return Err(non_finite("f", f, fv, q.x));
                }
                let l = TriangleGeometry::barycentric(q.xi);
                for i in 0..3 {
                    r[i] += q.weight * fv * l[i];
                }
            }
            Ok(r)
        })
        .collect();
    for (r, dofs) in local?.iter().zip(&topo.triangle_dofs) {
        for i in 0..3 {
            load[dofs[i]] += r[i];
        }
    }
    Ok(load)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::{PSpace, Rectangle, Segment, USpace};

    fn mesh(level: u32) -> Mesh {
        crate::mesh::structured::structured(
            crate::problem::UNIT_SQUARE,
            [4, 4],
            &[Segment {
                a: [-0.5, 0.0],
                b: [0.5, 0.0],
            }
            .into()],
            level,
        )
        .unwrap()
    }

    /// The system of `m` with the u topology `topo` and the continuous p, source `f`, Dirichlet
    /// data `g` and p mass `p_mass`.
    fn assemble_with_continuous_p(
        m: &Mesh,
        topo: &UTopology,
        f: &Expr,
        g: &Expr,
        p_mass: PMass,
    ) -> System {
        assemble(m, topo, &m.p_topology(PSpace::Continuous), f, g, p_mass).unwrap()
    }

    /// A sweep writes every δ into one matrix: after any earlier δ its values are bit for bit
    /// K(0) + δ ∂K/∂δ computed afresh from the full ∂K/∂δ (the direct formula, without the
    /// shared pattern), and ‖∂K/∂δ‖₁ is the mass matrix's, |Ω|-sized (row sums of M are the hat functions'
    /// integrals: at most the area of a vertex's patch / 3).
    #[test]
    fn set_delta_writes_k_of_delta_bit_for_bit_after_any_sweep() {
        let m = mesh(1);
        let topo = m.u_topology(USpace::Broken);
        for p_mass in [PMass::Consistent, PMass::Lumped] {
            let f = Expr::parse("sin(x)*y").unwrap();
            let sys = assemble_with_continuous_p(&m, &topo, &f, &Expr::constant(0.0), p_mass);
            let full = sys.delta_values();
            assert!(
                sys.delta_entries.len() < full.len() / 2,
                "only the u–u block"
            );
            let mut k = sys.base.clone();
            for delta in [1.0, 1e-2, 0.0, 1e-4, 3e-7] {
                sys.set_delta(&mut k, delta);
                for (i, (&got, (&v, &d))) in k
                    .values
                    .iter()
                    .zip(sys.base.values.iter().zip(&full))
                    .enumerate()
                {
                    let want = if delta != 0.0 { v + delta * d } else { v };
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "{p_mass} δ = {delta} entry {i}"
                    );
                }
            }
            let norm = sys.base.norm1_with(&full);
            assert_eq!(sys.delta_norm1, norm);
            assert!(norm > 0.0 && norm < 4.0, "{norm}");
        }
    }

    #[test]
    fn mass_sums_to_area_and_b_exact_on_linear_fields() {
        for space in [USpace::Continuous, USpace::Broken] {
            let m = mesh(1);
            let topo = m.u_topology(space);
            let sys = assemble_with_continuous_p(
                &m,
                &topo,
                &Expr::constant(0.0),
                &Expr::constant(0.0),
                PMass::Consistent,
            );
            let n_p = sys.n_p;
            // Σ_ij M_ij = |Ω| = 4 (−∂K/∂δ on the u block)
            let delta_values = sys.delta_values();
            let total: f64 = {
                let mut s = 0.0;
                for c in 0..sys.base.n {
                    for idx in sys.base.col_ptr[c]..sys.base.col_ptr[c + 1] {
                        let r = sys.base.row_idx[idx];
                        let v = -delta_values[idx];
                        s += if r == c { v } else { 2.0 * v };
                    }
                }
                s
            };
            assert!((total - 4.0).abs() < 1e-12, "{space}: ΣM = {total}");
            // B̃ on p = (1, 0) everywhere with u = x: B P = ∫ v div p = 0 and the bubble-free
            // identity (G̃ P + B̃ᵀU)_k = ∫_Γ u q_k·n for u linear, p = ∇u (exact for linear u).
            let k = sys.base.to_dense_rows();
            let mut x = vec![0.0; sys.n()];
            for (v, pt) in m.vertices.iter().enumerate() {
                x[2 * v] = 1.0;
                x[2 * v + 1] = 2.0;
                let _ = pt;
            }
            for (dof, &v) in topo.dof_vertex.iter().enumerate() {
                x[n_p + dof] = m.vertices[v][0] + 2.0 * m.vertices[v][1];
            }
            let g = Expr::parse("x + 2*y").unwrap();
            let sys_g =
                assemble_with_continuous_p(&m, &topo, &Expr::constant(0.0), &g, PMass::Consistent);
            for r in 0..n_p {
                let kx: f64 = (0..sys.n()).map(|c| k[r][c] * x[c]).sum();
                assert!(
                    (kx - sys_g.rhs[r]).abs() < 1e-12,
                    "{space}: p row {r}: {kx} vs {}",
                    sys_g.rhs[r]
                );
            }
            // u rows: B̃ P − C U = −∫ v div p − 0.7 ∫∇u∇v... with div p = 0 and ∇u = p: check
            // B̃ P = C U (the condensation of a consistent gradient field leaves no bubble).
            for r in n_p..sys.n() {
                let kx: f64 = (0..sys.n()).map(|c| k[r][c] * x[c]).sum();
                assert!(kx.abs() < 1e-12, "{space}: u row {r}: {kx}");
            }
        }
    }

    /// ∫_T λ0^a λ1^b λ2^c = a! b! c! 2|T| / (a + b + c + 2)!.
    fn barycentric_moment(area: f64, powers: [usize; 3]) -> f64 {
        let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
        let [a, b, c] = powers;
        fact(a) * fact(b) * fact(c) * 2.0 * area / fact(a + b + c + 2)
    }

    /// ∫_T (x² + 3y) λ_i exactly: x = Σ x_j λ_j, y = Σ y_j λ_j and the barycentric moments.
    fn exact_polynomial_load(geo: &TriangleGeometry, i: usize) -> f64 {
        let v = geo.vertices;
        let e = |k: usize| {
            let mut p = [0; 3];
            p[k] = 1;
            p
        };
        let add = |a: [usize; 3], b: [usize; 3]| [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
        let mut total = 0.0;
        for j in 0..3 {
            for k in 0..3 {
                let powers = add(add(e(i), e(j)), e(k));
                total += v[j][0] * v[k][0] * barycentric_moment(geo.area, powers);
            }
            total += 3.0 * v[j][1] * barycentric_moment(geo.area, add(e(i), e(j)));
        }
        total
    }

    /// ∫_T sin(z) λ_i exactly (to rounding), z = a x + b y, by the Hermite–Genocchi formula:
    /// with z_j the values at the vertices, ∫_T λ_i g(z) = 2|T| G[z_0, z_1, z_2, z_i] for G‴ = g,
    /// here G = cos. The divided difference (z_i repeated) is summed as its Taylor series about
    /// the mean c of the nodes, free of cancellation: G[w + c] = Σ_{m≥3} G⁽ᵐ⁾(c)/m! h_{m−3}(w),
    /// h_n the complete homogeneous symmetric polynomial of the shifted nodes w.
    fn exact_sine_load(geo: &TriangleGeometry, i: usize, [a, b]: [f64; 2]) -> f64 {
        let z = geo.vertices.map(|p| a * p[0] + b * p[1]);
        let nodes = [z[0], z[1], z[2], z[i]];
        let c = nodes.iter().sum::<f64>() / 4.0;
        const TERMS: usize = 40;
        let mut h = [0.0; TERMS];
        h[0] = 1.0;
        for w in nodes.map(|z| z - c) {
            for n in 1..TERMS {
                h[n] += w * h[n - 1];
            }
        }
        let mut factorial = 6.0; // 3!
        let mut sum = 0.0;
        for m in 3..TERMS + 3 {
            if m > 3 {
                factorial *= m as f64;
            }
            let derivative = (c + m as f64 * std::f64::consts::FRAC_PI_2).cos();
            sum += derivative / factorial * h[m - 3];
        }
        2.0 * geo.area * sum
    }

    /// The load F_i = ∫ f φ_i of the assembled system equals the exactly integrated value, for
    /// a polynomial f = x² + 3y and for f = sin(x + 0.7y), on the 8 triangles of a sheared and
    /// perturbed 2 × 2 grid (no right angles, no two sides alike). A load that evaluated f
    /// anywhere but at the quadrature points (a vertex, the centroid) fails this.
    #[test]
    fn load_vector_is_the_exact_integral_of_f_times_the_hat_functions() {
        let mut m = crate::mesh::structured::structured(
            Rectangle {
                min: [0.2, -0.3],
                max: [0.5, -0.1],
            },
            [2, 2],
            &[],
            0,
        )
        .unwrap();
        for p in &mut m.vertices {
            *p = [p[0] + 0.3 * p[1], p[1] - 0.1 * p[0]];
        }
        m.vertices[4][0] += 0.02;
        m.vertices[4][1] -= 0.01;
        assert_eq!(m.triangles.len(), 8);
        let topo = m.u_topology(USpace::Continuous);
        type ExactLoad = fn(&TriangleGeometry, usize) -> f64;
        let cases: [(&str, ExactLoad); 2] = [
            ("x^2 + 3*y", exact_polynomial_load),
            ("sin(x + 0.7*y)", |g, i| exact_sine_load(g, i, [1.0, 0.7])),
        ];
        for (source, exact) in cases {
            let f = Expr::parse(source).unwrap();
            let sys =
                assemble_with_continuous_p(&m, &topo, &f, &Expr::constant(0.0), PMass::Consistent);
            let mut want = vec![0.0; topo.n_dofs];
            for (t, dofs) in m.triangles.iter().zip(&topo.triangle_dofs) {
                let geo = TriangleGeometry::new(t.map(|v| m.vertices[v]));
                assert!(geo.area > 0.0);
                for i in 0..3 {
                    want[dofs[i]] += exact(&geo, i);
                }
            }
            let scale = want.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            assert!(scale > 1e-3, "{source}: {scale}");
            for (dof, w) in want.iter().enumerate() {
                let got = -sys.rhs[sys.n_p + dof];
                assert!(
                    (got - w).abs() <= 1e-12 * scale,
                    "{source}: F[{dof}] = {got:e}, exact {w:e}"
                );
            }
        }
    }
}
