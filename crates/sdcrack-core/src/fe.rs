//! Finite elements on triangles: quadrature rules, the P1 element for u and the MINI element
//! (P1 ⊕ cubic bubble, paper §3) for p, with the bubble's static condensation.

pub mod mini;
pub mod p1;
pub mod quadrature;
