//! sdcrack — the smooth-domain mixed method for a crack with unilateral contact
//! (Belhachmi, Sac-Epée, Sokolowski, C. R. Math. 338 (2004) 499–504).
//!
//! The pipeline, one module per stage, data flowing one way:
//! 1. [`scene`]: the TOML scene and its expressions, validated;
//! 2. [`mesh`]: structured nested triangulations, the crack chain, the u-space topologies;
//! 3. [`fe`] + [`assembly`]: P1/MINI elements, bubbles condensed, the system of paper (15);
//! 4. [`linalg`] + [`contact`]: sparse LDLᵀ of K(δ), the crack LCP of M0 | M1 | M1star;
//!    [`krylov`]: PCG on the lumped Schur complement, the iterative alternative that
//!    `sdcrack bench` measures (the solver keeps the direct route);
//! 5. [`norms`] + [`output`]: errors against exact solutions, `summary.json`, HDF5/XDMF fields.
//!
//! [`study`] drives the stages over levels, u spaces, δ and multipliers; [`references`] runs the
//! dolfinx and FreeFEM reference solvers the scene asks for; [`cli`] is the binary's command line.

// Element loops index local matrices by (i, j, k) exactly as the formulas do.
#![allow(clippy::needless_range_loop)]

pub mod assembly;
pub mod bench;
pub mod cli;
pub mod contact;
pub mod expr;
pub mod fe;
pub mod geometry;
pub mod krylov;
pub mod linalg;
pub mod mesh;
pub mod multiplier;
pub mod norms;
pub mod ordering;
pub mod output;
pub mod plain;
pub mod problem;
pub mod references;
pub mod scene;
pub mod study;
