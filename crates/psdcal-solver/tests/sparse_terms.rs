//! Sparse terms (`add_columns`) against the same terms written densely
//! (`add`): the same normal equations, the same step, the same Schur
//! complement.

use nalgebra::DMatrix;
use psdcal_solver::{NormalEquations, ResidualTerm};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn sparse_and_dense_terms_give_the_same_normal_equations_and_step() {
    let (p, n) = (20, 5);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut dense = NormalEquations::zeros(p, n);
    let mut sparse = NormalEquations::zeros(p, n);
    for k in 0..200 {
        let d = if k % 3 == 0 { 3 } else { 2 };
        let start = rng.random_range(0..p - 7);
        let columns: Vec<usize> = (start..start + 6).chain([p - 1]).collect();
        let r: Vec<f64> = (0..d).map(|_| rng.random_range(-1.0..1.0)).collect();
        let a: Vec<f64> = (0..d * columns.len())
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        let b: Vec<f64> = (0..d * 6).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut full = vec![0.0; d * p];
        for (j, &c) in columns.iter().enumerate() {
            full[d * c..d * c + d].copy_from_slice(&a[d * j..d * j + d]);
        }
        let block = (k % 4 != 3).then_some((k % n, &b[..]));
        let w = 0.5 + (k % 2) as f64;
        dense.add(
            w,
            &ResidualTerm {
                r: &r,
                a: &full,
                block,
            },
        );
        sparse.add_columns(
            w,
            &ResidualTerm {
                r: &r,
                a: &a,
                block,
            },
            &columns,
        );
    }
    // A prior on every parameter keeps the system regular.
    for j in 0..p {
        dense.u[(j, j)] += 1.0;
        sparse.u[(j, j)] += 1.0;
    }
    dense.finish();
    sparse.finish();
    let close = |x: &DMatrix<f64>, y: &DMatrix<f64>| (x - y).norm() <= 1e-12 * (1.0 + x.norm());
    assert!(close(&dense.u, &sparse.u));
    for i in 0..n {
        assert!(close(&dense.w[i], &sparse.w[i]));
        assert!((dense.v[i] - sparse.v[i]).norm() < 1e-12);
    }
    assert!(sparse.sparse_rows && !dense.sparse_rows);
    let (s1, s2) = (dense.solve(1e-3).unwrap(), sparse.solve(1e-3).unwrap());
    assert!((&s1.da - &s2.da).norm() < 1e-10 * (1.0 + s1.da.norm()));
    for (x, y) in s1.db.iter().zip(&s2.db) {
        assert!((x - y).norm() < 1e-10 * (1.0 + x.norm()));
    }
    // The Schur complement (the covariance's) over the non-zero rows alone.
    let (c1, c2) = (
        dense.schur_complement().unwrap(),
        sparse.schur_complement().unwrap(),
    );
    assert!((&c1 - &c2).norm() <= 1e-10 * (1.0 + c1.norm()));
    assert_eq!(c2, c2.transpose());
}
