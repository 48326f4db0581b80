//! HDF5 + XDMF 3 field files: [`write_fields`] writes the fields of every solved case;
//! [`write_h5_only`] writes the same HDF5 file without the XDMF series (the results folder's
//! `verification.h5`, kept for the compare tool's recomputation, not for viewers).
//!
//! # Files
//!
//! For `write_fields(DIR, STEM, meshes, cases)`:
//!
//! ```text
//! DIR/STEM.h5                          all heavy data (HDF5)
//! DIR/STEM/CASE.xdmf                   one case's triangle grid: one state (meshio.read)
//! DIR/STEM/CASE.crack.xdmf             its crack polylines (when it has a crack)
//! DIR/STEM/SERIES.series.xdmf          the triangle grids of one series, one time step per case
//!                                      (meshio.xdmf.TimeSeriesReader)
//! DIR/STEM/SERIES.crack.series.xdmf    the crack polylines of the same series
//! ```
//!
//! A *series* is a list of cases on one mesh that a viewer walks through with its time slider;
//! the solver makes one series per (level, u space, multiplier, p mass), whose steps are the δ
//! sweep in the order solved (δ decreasing, so the slider walks δ → 0).
//!
//! The convention, the same in the reference scripts' fields (compare/sdshared/sdfields.py):
//! a file `NAME.xdmf` holds one state, a single grid, which `meshio.read` and ParaView read;
//! a file `NAME.series.xdmf` holds a temporal collection, which `meshio.xdmf.TimeSeriesReader`
//! and ParaView read. No one file serves both meshio readers: `meshio.read` accepts exactly one
//! grid with no `Time`, and `TimeSeriesReader` needs a temporal collection.
//!
//! `write_h5_only(DIR, STEM, meshes, cases)` writes `DIR/STEM.h5` alone: the same datasets with
//! the same values and attributes as `write_fields` would, validated and committed the same way;
//! no series folder.
//!
//! # HDF5 datasets (`STEM.h5`)
//!
//! ```text
//! /meshes/KEY/points               f64 (N, 3)  mesh nodes, z = 0
//! /meshes/KEY/triangles            i64 (T, 3)  node indices, 0-based
//! /cases/CASE/mesh                 soft link to /meshes/KEY
//! /cases/CASE/u                    f64 (N,)    optional
//! /cases/CASE/p                    f64 (N, 3)  optional, z = 0
//! /cases/CASE/p_bubble             f64 (T, 2)  with p: bubble coefficients of the MINI p per
//!                                              triangle (p_h = Σ p_i λ_i + p_bubble · 27 λ0 λ1 λ2)
//! /cases/CASE/crack/points         f64 (N_c, 3) crack nodes, z = 0 (all cracks, concatenated)
//! /cases/CASE/crack/segments       i64 (I, 2)  the crack segments [k, k+1], within each crack
//! /cases/CASE/crack/lambda         f64 (N_c,) per node or (I,) per segment, optional
//! /cases/CASE/crack/jump           f64 (N_c,)  per node, optional: [u_h] = u⁺ − u⁻ (see
//!                                              [`CaseFields::jump`])
//! /cases/CASE/NAME                 f64 (N,)    a constant field of [`CaseFields::constants`]
//! /cases/CASE/crack/NAME           f64 (I+1,)  the same on the crack nodes
//! /cases/CASE/FIELD                f64 (N or T[, C]) a further field ([`CaseFields::extra`]) on
//!                                              the mesh's nodes or cells, C = 3 (vector) or 9
//!                                              (tensor) components
//! /cases/CASE/crack/FIELD          f64 (N_c or I[, C]) the same on the crack
//! ```
//!
//! The group `/cases/CASE` and every field dataset in it (`u`, `p`, `p_bubble`, `crack/lambda`,
//! `crack/jump`, the constants) carry the case's [`CaseFields::metadata`] as HDF5 attributes (the solver's:
//! `level`, `h`, `u_space`, `multiplier`, `p_mass`, `delta`), plus `series` (text) and `step` (integer).
//! The solver's only constant field is `delta`: ParaView ignores XDMF `Information` and shows no
//! step names, so δ is also a point attribute whose value (its range in the information panel, or
//! the "Annotate Attribute Data" filter) says which δ the time slider is on; meshio reads it as
//! point data. (A `Center="Grid"` attribute would cost one number, but meshio rejects it.)
//!
//! The elastic cases (docs/elasticity.md, "The run") use further fields only: their mesh is the
//! *broken* mesh of their level (3 points per triangle, so that σ_h and u*, linear per triangle
//! and discontinuous, are node fields), their crack grid one segment per crack edge with its own
//! two points (the opening, slip, pressure and closed flags are discontinuous at crack nodes).
//!
//! Each mesh is stored once, however many cases use it; only meshes used by at least one case are
//! written. A case whose `crack_points` is empty (and has no `lambda` or `jump`) has no `crack`
//! group and no crack grid. Data are stored contiguously, uncompressed.
//!
//! # XDMF series (`STEM/SERIES.series.xdmf`, `STEM/SERIES.crack.series.xdmf`)
//!
//! ```text
//! <Xdmf Version="3.0">
//!   <Domain>
//!     <Grid Name="SERIES" GridType="Collection" CollectionType="Temporal">
//!       <Grid Name="CASE" GridType="Uniform">       one per case of the series, in order
//!         <Time Value="k"/>                         k = 0, 1, ...: the step's index
//!         <Information Name="delta" Value="0.01"/>  the case's metadata, one element per key
//!         Triangle topology, XYZ geometry,
//!         Attributes u (Scalar), p (Vector), delta (Scalar), Center="Node"
//!       ...
//! ```
//!
//! The crack file has the same shape with Polyline topology (`NodesPerElement="2"`) and the
//! attributes `lambda` (Scalar, `Center="Node"` or `"Cell"`), `jump` (Scalar, Node) and `delta`
//! (Scalar, Node). All `DataItem`s are `Format="HDF"`
//! and name the heavy file relative to the XDMF file (`../STEM.h5:/cases/CASE/u`); the steps of
//! a series point at the same `/meshes/KEY/...` datasets.
//!
//! This is the shape both clients read: ParaView's default XDMF 3 reader opens a temporal
//! collection as one dataset with time steps, and meshio 5's `meshio.xdmf.TimeSeriesReader`
//! reads the points and cells of the first step and the data and `Time` of every step (it skips
//! `Information`, and would reject `Center="Grid"` attributes, which are therefore not used).
//! No file holds more than one series: overlapping grids of several levels or δ in one spatial
//! collection are what a viewer cannot show.
//!
//! # XDMF states (`STEM/CASE.xdmf`, `STEM/CASE.crack.xdmf`)
//!
//! One `<Grid Name="CASE" GridType="Uniform">` directly in the `Domain`, with the same topology,
//! geometry and attributes as the case's step in its series and neither `Time` nor
//! `Information`.
//!
//! # Names
//!
//! `STEM`, mesh keys, case names and series names are used as file names, HDF5 link names and
//! inside XDMF `DataItem`s, so they must be non-empty, not `.` or `..`, and free of `/`, `\`,
//! `:` and control characters. XML special characters are allowed and escaped.
//!
//! # Atomicity
//!
//! Everything is validated before anything is written. The outputs are then written under
//! temporary names in `DIR` (`.STEM.h5.tmp-PID-N`, folder `.STEM.tmp-PID-N`), fsynced, and
//! renamed in the order `STEM.h5`, `STEM/`. Each rename is atomic; an existing `STEM/` folder is
//! first moved aside (`.STEM.old-PID-N`) and deleted after the new one is in place. On any error
//! before the renames every temporary is removed and existing files under the final names are
//! left untouched. Whether overwriting is allowed is the caller's decision: this module always
//! replaces.

mod data;
mod write;
mod xml;

pub use data::{CaseFields, Centering, Field, FieldKind, GridPart, MeshData, Meta};
pub use write::{series_file, state_file, write_fields, write_h5_only, OutputError, SERIES_SUFFIX};
