use super::*;

use super::ldlt::PIVOT_DELTA_REL;
use super::refine::{inf_norm, residual};
use fastrand::Rng;

/// Dense row-major copy of the full symmetric matrix.
fn dense(m: &SymCsc) -> Vec<f64> {
    let n = m.n;
    let mut a = vec![0.0; n * n];
    for j in 0..n {
        for p in m.col_ptr[j]..m.col_ptr[j + 1] {
            let i = m.row_idx[p];
            a[i * n + j] = m.values[p];
            a[j * n + i] = m.values[p];
        }
    }
    a
}

/// Dense Gaussian elimination with partial pivoting (row-major `a`).
fn dense_solve(mut a: Vec<f64>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for k in 0..n {
        let p = (k..n)
            .max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))
            .unwrap();
        for c in 0..n {
            a.swap(k * n + c, p * n + c);
        }
        b.swap(k, p);
        for i in k + 1..n {
            let f = a[i * n + k] / a[k * n + k];
            for c in k..n {
                a[i * n + c] -= f * a[k * n + c];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|c| a[k * n + c] * x[c]).sum();
        x[k] = (b[k] - s) / a[k * n + k];
    }
    x
}

fn rel_residual(m: &SymCsc, b: &[f64], x: &[f64]) -> f64 {
    let mut r = vec![0.0; m.n];
    residual(m, b, x, &mut r) / inf_norm(b)
}

/// A number in `[-1, 1)`.
fn symmetric_unit(rng: &mut Rng) -> f64 {
    2.0 * rng.f64() - 1.0
}

fn random_vec(rng: &mut Rng, n: usize) -> Vec<f64> {
    (0..n).map(|_| symmetric_unit(rng)).collect()
}

/// Random sparse SPD matrix: random symmetric off-diagonals, diagonally dominant.
fn random_spd(n: usize, per_row: usize, seed: u64) -> SymCsc {
    let mut rng = Rng::with_seed(seed);
    let mut trip = Vec::new();
    let mut rowsum = vec![0.0; n];
    for i in 0..n {
        for _ in 0..per_row {
            let j = rng.usize(..n);
            if j != i {
                let v = symmetric_unit(&mut rng);
                trip.push((i, j, v));
                rowsum[i] += v.abs();
                rowsum[j] += v.abs();
            }
        }
    }
    for (i, s) in rowsum.iter().enumerate() {
        trip.push((i, i, s + 0.5 + symmetric_unit(&mut rng).abs()));
    }
    SymCsc::from_triplets(n, &trip).unwrap()
}

/// Quasi-definite saddle matrix `[[G, Bᵀ], [B, −s_scale·S]]` on an `m × m` grid:
/// `G` = 5-point Laplacian + I (SPD), `S` = Neumann 5-point Laplacian (singular,
/// constants in its kernel), `B` = identity coupling + two random couplings to
/// nearby grid nodes (full row rank, so `K` is nonsingular even for
/// `s_scale = 0`). Returns `(K, signs, n_g)`.
fn saddle_scaled(m: usize, seed: u64, s_scale: f64) -> (SymCsc, Vec<i8>, usize) {
    let mut rng = Rng::with_seed(seed);
    let ng = m * m;
    let ns = m * m;
    let id = |i: usize, j: usize| i * m + j;
    let mut trip = Vec::new();
    for i in 0..m {
        for j in 0..m {
            let k = id(i, j);
            trip.push((k, k, 4.0 + 1.0));
            let mut deg = 0.0;
            for (ii, jj) in [(i + 1, j), (i, j + 1)] {
                if ii < m && jj < m {
                    let l = id(ii, jj);
                    trip.push((l, k, -1.0));
                    trip.push((ng + l, ng + k, s_scale));
                }
            }
            for (ii, jj) in [
                (i.wrapping_sub(1), j),
                (i + 1, j),
                (i, j.wrapping_sub(1)),
                (i, j + 1),
            ] {
                if ii < m && jj < m {
                    deg += 1.0;
                }
            }
            trip.push((ng + k, ng + k, -s_scale * deg));
            trip.push((ng + k, k, 1.0));
            for _ in 0..2 {
                let ii = (i + rng.usize(..3)).saturating_sub(1).min(m - 1);
                let jj = (j + rng.usize(..3)).saturating_sub(1).min(m - 1);
                trip.push((ng + k, id(ii, jj), 0.3 * symmetric_unit(&mut rng)));
            }
        }
    }
    let signs = (0..ng + ns).map(|i| if i < ng { 1 } else { -1 }).collect();
    (SymCsc::from_triplets(ng + ns, &trip).unwrap(), signs, ng)
}

fn saddle(m: usize, seed: u64) -> (SymCsc, Vec<i8>, usize) {
    saddle_scaled(m, seed, 1.0)
}

#[test]
fn random_spd_matches_dense() {
    let n = 200;
    let k = random_spd(n, 3, 7);
    let sym = SymbolicLdlt::analyze(&k).unwrap();
    let f = Ldlt::factor(&sym, &k, &vec![1; n]).unwrap();
    assert_eq!(f.stats().positive_pivots, n);
    assert_eq!(f.stats().regularized_pivots, 0);
    let mut rng = Rng::with_seed(3);
    let b = random_vec(&mut rng, n);
    let mut x = b.clone();
    f.solve_in_place(&mut x);
    let res = rel_residual(&k, &b, &x);
    assert!(res < 1e-12, "residual {res}");
    let xd = dense_solve(dense(&k), b.clone());
    let err = x
        .iter()
        .zip(&xd)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / inf_norm(&xd);
    assert!(err < 1e-12, "difference to dense solve {err}");
}

fn check_saddle(m: usize) {
    let (k, signs, ng) = saddle(m, 11);
    let n = k.n;
    let sym = SymbolicLdlt::analyze(&k).unwrap();
    assert!(sym.factor_nnz() >= k.row_idx.len());
    let f = Ldlt::factor(&sym, &k, &signs).unwrap();
    let st = f.stats();
    assert_eq!(st.positive_pivots, ng, "{st:?}");
    assert_eq!(st.negative_pivots, n - ng, "{st:?}");
    assert!(st.min_abs_pivot > 0.0 && st.max_abs_pivot.is_finite());
    let mut rng = Rng::with_seed(5);
    let b = random_vec(&mut rng, n);
    let mut x = vec![0.0; n];
    let rel = f.solve_refined(&k, &b, &mut x, 10, 1e-14);
    let check = rel_residual(&k, &b, &x);
    assert_eq!(rel, check);
    assert!(rel < 1e-12, "m = {m}: residual {rel}, stats {st:?}");
    // b = 0 gives x = 0.
    let mut z = vec![1.0; n];
    assert_eq!(f.solve_refined(&k, &vec![0.0; n], &mut z, 3, 1e-14), 0.0);
    assert!(z.iter().all(|&v| v == 0.0));
}

/// `trailing_inverse` agrees with column-by-column solves, on the simplicial (m = 10) and
/// supernodal (m = 60) paths, and refuses unknowns that are not eliminated last.
#[test]
fn trailing_inverse_matches_solves() {
    for m in [10, 60] {
        let (k, signs, _) = saddle(m, 5);
        let n = k.n;
        let picked: Vec<usize> = (0..n).filter(|i| i % 7 == 2).take(12).collect();
        let mut order: Vec<usize> = (0..n).filter(|i| !picked.contains(i)).collect();
        order.extend(picked.iter().rev());
        let sym = SymbolicLdlt::analyze_ordered(&k, &order).unwrap();
        let f = Ldlt::factor(&sym, &k, &signs).unwrap();
        let inv = f.trailing_inverse(&picked).unwrap();
        let c = picked.len();
        let mut worst = 0.0f64;
        let mut scale = 0.0f64;
        for (b, &j) in picked.iter().enumerate() {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            f.solve_in_place(&mut e);
            for (a, &i) in picked.iter().enumerate() {
                worst = worst.max((inv[a * c + b] - e[i]).abs());
                scale = scale.max(e[i].abs());
            }
        }
        assert!(worst <= 1e-12 * scale, "m = {m}: {worst:e} vs {scale:e}");
        assert!(f.trailing_inverse(&[0]).is_none() || order[n - 1] == 0);
        let amd = Ldlt::factor(&SymbolicLdlt::analyze(&k).unwrap(), &k, &signs).unwrap();
        let trailing_amd = amd.symbolic.perm().unwrap().arrays().0[n - 1];
        assert!(amd.trailing_inverse(&[trailing_amd]).is_some());
        assert!(amd.trailing_inverse(&[(trailing_amd + 1) % n]).is_none());
    }
    let (k, _, _) = saddle(10, 5);
    assert!(SymbolicLdlt::analyze_ordered(&k, &[0, 0]).is_err());
    let mut order: Vec<usize> = (0..k.n).collect();
    order[1] = 0;
    assert!(SymbolicLdlt::analyze_ordered(&k, &order).is_err());
}

#[test]
fn cholesky_solve_matches_ldlt() {
    let k = random_spd(300, 4, 9);
    let mut rng = Rng::with_seed(4);
    let b = random_vec(&mut rng, k.n);
    let mut x = b.clone();
    let t = cholesky_solve(&k, &mut x).unwrap();
    assert!(t.factor_nnz >= k.n);
    assert!(rel_residual(&k, &b, &x) < 1e-13);
    let mut not_spd = k.clone();
    not_spd.values.iter_mut().for_each(|v| *v = -*v);
    assert!(cholesky_solve(&not_spd, &mut x).is_err());
}

#[test]
fn refactor_and_block_refinement_match_single_solves() {
    let (k, signs, _) = saddle(60, 3);
    let sym = SymbolicLdlt::analyze(&k).unwrap();
    let first = Ldlt::factor(&sym, &k, &signs).unwrap();
    let mut shifted = k.clone();
    shifted.values.iter_mut().for_each(|v| *v *= 1.5);
    let again = Ldlt::refactor(&sym, &shifted, &signs, Some(first)).unwrap();
    let fresh = Ldlt::factor(&sym, &shifted, &signs).unwrap();
    assert_eq!(again.values, fresh.values);
    let mut rng = Rng::with_seed(8);
    let mut b = random_vec(&mut rng, 3 * k.n);
    b[k.n..2 * k.n].fill(0.0);
    let mut x = vec![0.0; b.len()];
    let rel = again.solve_refined_many(&shifted, &b, &mut x, 3, 1e-15);
    assert_eq!(rel.len(), 3);
    assert_eq!(rel[1], 0.0);
    for j in [0, 2] {
        let cols = j * k.n..(j + 1) * k.n;
        assert!(rel[j] < 1e-14, "{rel:?}");
        assert!(rel_residual(&shifted, &b[cols.clone()], &x[cols]) < 1e-14);
    }
    assert!(x[k.n..2 * k.n].iter().all(|&v| v == 0.0));
}

/// The estimate is a lower bound of κ₁ from the dense inverse, and within a factor 3 of it.
#[test]
fn condition_estimate_brackets_the_dense_condition_number() {
    for (m, seed) in [(10, 1), (60, 2)] {
        let (k, signs, _) = saddle(m, seed);
        let f = Ldlt::factor(&SymbolicLdlt::analyze(&k).unwrap(), &k, &signs).unwrap();
        let n = k.n;
        let mut inv_norm1 = 0.0f64;
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            f.solve_in_place(&mut e);
            inv_norm1 = inv_norm1.max(e.iter().map(|v| v.abs()).sum());
        }
        let a = dense(&k);
        let k_norm1 = (0..n)
            .map(|j| (0..n).map(|i| a[i * n + j].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        assert!((k.norm1() - k_norm1).abs() <= 1e-12 * k_norm1);
        let exact = k_norm1 * inv_norm1;
        let est = k.norm1() * f.inverse_norm1_estimate();
        assert!(
            est <= exact * (1.0 + 1e-10) && est >= exact / 3.0,
            "m = {m}: {est:e} vs {exact:e}"
        );
    }
}

#[test]
fn componentwise_backward_error_conventions() {
    assert_eq!(
        componentwise_backward_error(&[0.0, 1e-16], &[0.0, 1.0]),
        1e-16
    );
    assert_eq!(componentwise_backward_error(&[-2.0, 1.0], &[4.0, 8.0]), 0.5);
    assert_eq!(
        componentwise_backward_error(&[1e-300], &[0.0]),
        f64::INFINITY
    );
    assert!(componentwise_backward_error(&[0.0, f64::NAN], &[1.0, 1.0]).is_nan());
}

#[test]
fn saddle_m10() {
    check_saddle(10);
}

#[test]
fn saddle_m60() {
    check_saddle(60);
}

/// Pure saddle point (`S = 0`): AMD eliminates many `S` rows before their
/// `G` neighbours, so zero pivots appear and are regularized to `−delta`
/// (simplicial path for m = 20, supernodal for m = 60); refinement against the
/// exact matrix recovers full accuracy.
#[test]
fn zero_s_block_is_regularized_and_refined() {
    for m in [20, 60] {
        let (k, signs, ng) = saddle_scaled(m, 11, 0.0);
        let sym = SymbolicLdlt::analyze(&k).unwrap();
        let f = Ldlt::factor(&sym, &k, &signs).unwrap();
        let st = f.stats();
        assert!(st.regularized_pivots > 0, "{st:?}");
        assert_eq!(st.positive_pivots, ng, "{st:?}");
        assert_eq!(st.negative_pivots, k.n - ng, "{st:?}");
        let mut rng = Rng::with_seed(2);
        let b = random_vec(&mut rng, k.n);
        let mut x = vec![0.0; k.n];
        let rel = f.solve_refined(&k, &b, &mut x, 10, 1e-14);
        assert!(rel < 1e-12, "m = {m}: residual {rel}");
    }
}

#[test]
fn wrong_sign_and_singular_pivots_are_regularized() {
    // [[1, 0], [0, 0]] with signs (+, -): second pivot is zero -> -delta.
    let k = SymCsc::from_triplets(2, &[(0, 0, 1.0), (1, 1, 0.0), (1, 0, 0.0)]).unwrap();
    let sym = SymbolicLdlt::analyze(&k).unwrap();
    let f = Ldlt::factor(&sym, &k, &[1, -1]).unwrap();
    assert_eq!(f.stats().regularized_pivots, 1);
    assert_eq!(f.stats().negative_pivots, 1);
    assert_eq!(f.stats().min_abs_pivot, PIVOT_DELTA_REL);
    // diag(1, 2) with signs (+, -): wrong sign -> -delta.
    let k2 = SymCsc::from_triplets(2, &[(0, 0, 1.0), (1, 1, 2.0), (1, 0, 0.0)]).unwrap();
    let f2 = Ldlt::factor(&sym, &k2, &[1, -1]).unwrap();
    assert_eq!(f2.stats().regularized_pivots, 1);
    assert_eq!(f2.stats().negative_pivots, 1);
}

#[test]
fn symbolic_reuse_and_same_pattern() {
    let (k1, signs, _) = saddle(12, 1);
    let mut k2 = k1.clone();
    let mut rng = Rng::with_seed(9);
    // Same pattern, different values: scale G rows / perturb couplings.
    for j in 0..k2.n {
        for p in k2.col_ptr[j]..k2.col_ptr[j + 1] {
            if k2.row_idx[p] != j {
                k2.values[p] *= 1.0 + 0.2 * symmetric_unit(&mut rng);
            } else {
                k2.values[p] *= 1.5;
            }
        }
    }
    assert!(k1.same_pattern(&k2));
    let sym = SymbolicLdlt::analyze(&k1).unwrap();
    for k in [&k1, &k2] {
        let f = Ldlt::factor(&sym, k, &signs).unwrap();
        let b = random_vec(&mut rng, k.n);
        let mut x = vec![0.0; k.n];
        let rel = f.solve_refined(k, &b, &mut x, 5, 1e-15);
        assert!(rel < 1e-12, "residual {rel}");
    }
    // Different pattern: detected by same_pattern and refused by factor.
    let mut trip = Vec::new();
    for j in 0..k1.n {
        for p in k1.col_ptr[j]..k1.col_ptr[j + 1] {
            trip.push((k1.row_idx[p], j, k1.values[p]));
        }
    }
    trip.push((k1.n - 1, 0, 0.0));
    let k3 = SymCsc::from_triplets(k1.n, &trip).unwrap();
    assert!(!k1.same_pattern(&k3));
    assert!(!k1.same_pattern(&random_spd(5, 2, 1)));
    assert!(matches!(
        Ldlt::factor(&sym, &k3, &signs),
        Err(LinalgError::PatternMismatch)
    ));
    assert!(matches!(
        Ldlt::factor(&sym, &k1, &signs[1..]),
        Err(LinalgError::Dimension { .. })
    ));
    let mut bad = signs.clone();
    bad[3] = 0;
    assert!(matches!(
        Ldlt::factor(&sym, &k1, &bad),
        Err(LinalgError::InvalidSign { index: 3, value: 0 })
    ));
    let mut nan = k1.clone();
    nan.values[0] = f64::NAN;
    assert!(matches!(
        Ldlt::factor(&sym, &nan, &signs),
        Err(LinalgError::NonFinite)
    ));
    let mut broken = k1.clone();
    broken.row_idx.swap(0, 1);
    assert!(SymbolicLdlt::analyze(&broken).is_err());
}

#[test]
fn solve_many_matches_single_solves() {
    // (15, 7): one sequential block; (20, 100): 800 × 100 rhs, split over threads
    // whenever the rayon pool has more than one thread.
    for (m, ncols) in [(15, 7), (20, 100)] {
        let (k, signs, _) = saddle(m, 4);
        let n = k.n;
        let sym = SymbolicLdlt::analyze(&k).unwrap();
        let f = Ldlt::factor(&sym, &k, &signs).unwrap();
        let mut rng = Rng::with_seed(8);
        let b = random_vec(&mut rng, n * ncols);
        let mut many = b.clone();
        f.solve_many_in_place(&mut many, ncols);
        for c in 0..ncols {
            let mut one = b[c * n..(c + 1) * n].to_vec();
            f.solve_in_place(&mut one);
            let scale = inf_norm(&one);
            for (a, s) in many[c * n..(c + 1) * n].iter().zip(&one) {
                assert!((a - s).abs() <= 1e-13 * scale, "column {c}: {a} vs {s}");
            }
        }
        f.solve_many_in_place(&mut [], 0);
    }
}

#[test]
fn from_triplets_sums_mirrors_and_multiplies() {
    let n = 4;
    let trip = [
        (0, 0, 2.0),
        (0, 0, 1.0), // duplicate: 3
        (0, 2, 1.5), // upper: mirrored to (2, 0)
        (2, 0, 0.5), // same lower entry: 2.0 in total
        (3, 1, -1.0),
        (1, 1, 4.0),
        (3, 3, 5.0),
        (2, 2, 6.0),
        (3, 2, 0.0), // explicit zero kept in the pattern
    ];
    let k = SymCsc::from_triplets(n, &trip).unwrap();
    assert_eq!(k.col_ptr, vec![0, 2, 4, 6, 7]);
    assert_eq!(k.row_idx, vec![0, 2, 1, 3, 2, 3, 3]);
    assert_eq!(k.values, vec![3.0, 2.0, 4.0, -1.0, 6.0, 0.0, 5.0]);
    let a = dense(&k);
    let x = [1.0, -2.0, 0.5, 3.0];
    let mut y = [0.0; 4];
    k.mul_vec(&x, &mut y);
    for i in 0..n {
        let yi: f64 = (0..n).map(|j| a[i * n + j] * x[j]).sum();
        assert!((y[i] - yi).abs() < 1e-15);
    }
    assert_eq!(a[2], 2.0);
    assert_eq!(a[2 * n], 2.0);
    // Random larger check against the dense product.
    let big = random_spd(50, 4, 2);
    let ad = dense(&big);
    let mut rng = Rng::with_seed(1);
    let x = random_vec(&mut rng, 50);
    let mut y = vec![0.0; 50];
    big.mul_vec(&x, &mut y);
    for i in 0..50 {
        let yi: f64 = (0..50).map(|j| ad[i * 50 + j] * x[j]).sum();
        assert!((y[i] - yi).abs() < 1e-12);
    }
    assert!(matches!(
        SymCsc::from_triplets(2, &[(2, 0, 1.0)]),
        Err(LinalgError::IndexOutOfBounds {
            row: 2,
            col: 0,
            n: 2
        })
    ));
    assert!(matches!(
        SymCsc::from_triplets(2, &[(1, 0, f64::INFINITY)]),
        Err(LinalgError::NonFinite)
    ));
}

#[test]
fn empty_matrix() {
    let k = SymCsc::from_triplets(0, &[]).unwrap();
    let sym = SymbolicLdlt::analyze(&k).unwrap();
    let f = Ldlt::factor(&sym, &k, &[]).unwrap();
    let mut x: Vec<f64> = vec![];
    assert_eq!(f.solve_refined(&k, &[], &mut x, 2, 1e-12), 0.0);
    f.solve_in_place(&mut x);
}
