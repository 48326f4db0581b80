//! sdcrack-core — the maths and the study of the smooth-domain mixed method for a crack with
//! unilateral contact (Belhachmi, Sac-Epée, Sokolowski, C. R. Math. 338 (2004) 499–504).
//!
//! No file format lives here: this crate depends on no TOML, CLI or HDF5 crate. The
//! pipeline, one module per stage, data flowing one way:
//! 1. [`problem`] + [`expr`]: the problem's vocabulary and its expressions; [`scene`]: the
//!    validated scene (sdcrack-io parses it from TOML);
//! 2. [`mesh`] + [`geometry`]: structured, gmsh and file meshes, the crack chain, the u-space
//!    topologies;
//! 3. [`fe`] + [`assembly`]: P1/MINI elements, bubbles condensed, the system of paper (15);
//! 4. [`linalg`] + [`ordering`] + [`contact`] + [`multiplier`]: sparse LDLᵀ of K(δ), the crack
//!    LCP of M0 | M1 | M1star; [`krylov`]: PCG on the lumped Schur complement, the iterative
//!    alternative that `sdcrack bench` measures (the solver keeps the direct route);
//! 5. [`norms`]: errors against exact solutions.
//!
//! [`study`] drives the stages over levels, u spaces, δ and multipliers.

// Element loops index local matrices by (i, j, k) exactly as the formulas do.
#![allow(clippy::needless_range_loop)]

pub mod afw;
pub mod assembly;
pub mod case;
pub mod contact;
pub mod elasticity;
pub mod expr;
pub mod fe;
pub mod geometry;
pub mod krylov;
pub mod linalg;
pub mod mesh;
pub mod multiplier;
pub mod norms;
pub mod ordering;
pub mod problem;
pub mod scene;
pub mod study;
