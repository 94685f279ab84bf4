//! Rescaled localized RBF interpolation between non-matching interfaces (`contact::rbf`):
//! exact reproduction of constants, convergence on smooth fields, radii (Algorithm 1 of
//! `docs/method.md` 2.2 against twice the spacing), and the sparse rows and columns the contact
//! operators use: solved on patches of a large surface, and with wide supports, against the
//! whole `Phi_MM` factored here. Everything is deterministic.

use std::f64::consts::PI;

use internodes::contact::ContactSurface;
use internodes::contact::rbf::{DROP_TOL, Interpolation, interpolation_radii, support_radii};
use internodes::mesh::read_msh;

mod common;

/// Points on the circle of radius `radius` at the angles `theta`, in the plane z = 0 (2D).
fn arc(radius: f64, theta: &[f64]) -> Vec<[f64; 3]> {
    theta
        .iter()
        .map(|t| [radius * t.cos(), radius * t.sin(), 0.0])
        .collect()
}

/// `n + 1` angles covering `[a, b]`, uniformly spaced and then shifted by a deterministic
/// fraction `wobble` of the spacing at interior nodes (non-uniform, non-matching sets).
fn angles(a: f64, b: f64, n: usize, wobble: f64, seed: f64) -> Vec<f64> {
    let h = (b - a) / n as f64;
    (0..=n)
        .map(|k| {
            let shift = if k == 0 || k == n {
                0.0
            } else {
                wobble * h * (seed * k as f64).sin()
            };
            a + k as f64 * h + shift
        })
        .collect()
}

/// Grid of `(n + 1)^2` points on `[0, 1]^2`, with interior points shifted by `wobble * h`,
/// mapped to 3D by `map`.
fn patch(n: usize, wobble: f64, seed: f64, map: impl Fn(f64, f64) -> [f64; 3]) -> Vec<[f64; 3]> {
    let h = 1.0 / n as f64;
    let mut points = Vec::with_capacity((n + 1) * (n + 1));
    for i in 0..=n {
        for j in 0..=n {
            let interior = i > 0 && i < n && j > 0 && j < n;
            let (du, dv) = if interior {
                let k = (i * (n + 1) + j) as f64;
                (
                    wobble * h * (seed * k).sin(),
                    wobble * h * (1.3 * seed * k).cos(),
                )
            } else {
                (0.0, 0.0)
            };
            points.push(map(i as f64 * h + du, j as f64 * h + dv));
        }
    }
    points
}

fn plane(u: f64, v: f64) -> [f64; 3] {
    [u, v, 0.3]
}

/// Spherical cap of radius 1 around the north pole, parametrized by `[0, 1]^2`.
fn sphere_cap(u: f64, v: f64) -> [f64; 3] {
    let (theta, psi) = (0.3 + 0.5 * u, 1.2 * v);
    [
        theta.sin() * psi.cos(),
        theta.sin() * psi.sin(),
        theta.cos(),
    ]
}

/// Builds the interpolation from `sources` (radii by Algorithm 1) to `targets` and checks that
/// every target is covered, every row of R sums to one and a constant is reproduced.
fn check_constants(sources: &[[f64; 3]], targets: &[[f64; 3]]) {
    let radii = support_radii(sources).expect("radii");
    let interp = Interpolation::new(sources, &radii, targets).expect("interpolation");
    assert_eq!(interp.num_sources(), sources.len());
    assert_eq!(interp.num_targets(), targets.len());
    assert!(interp.uncovered_targets().is_empty());
    let r = interp.matrix().expect("matrix");
    assert_eq!(r.shape(), (targets.len(), sources.len()));
    for (t, row) in r.row_iter().enumerate() {
        let sum: f64 = row.iter().sum();
        assert!((sum - 1.0).abs() < 1e-14, "row {t} sums to {sum}");
    }
    // A constant vector field (3 interleaved components) is reproduced exactly.
    let c = [2.5, -7.0, 1e-3];
    let values: Vec<f64> = (0..sources.len()).flat_map(|_| c).collect();
    let out = interp.apply(&values, 3).expect("apply");
    for (t, v) in out.chunks_exact(3).enumerate() {
        for k in 0..3 {
            assert!(
                (v[k] - c[k]).abs() <= 1e-14 * c[k].abs(),
                "target {t}, component {k}: {} instead of {}",
                v[k],
                c[k]
            );
        }
    }
    // apply agrees with the dense matrix.
    let g: Vec<f64> = sources.iter().map(|p| p[0] - 2.0 * p[1] + p[2]).collect();
    let by_apply = interp.apply(&g, 1).expect("apply");
    let by_matrix = &r * nalgebra::DVector::from_vec(g);
    for (a, b) in by_apply.iter().zip(by_matrix.iter()) {
        assert!((a - b).abs() < 1e-12);
    }
}

#[test]
fn constants_are_reproduced_2d() {
    // Straight segment.
    let line = |n: usize, w: f64, s: f64| -> Vec<[f64; 3]> {
        angles(0.0, 2.0, n, w, s)
            .into_iter()
            .map(|x| [x, 0.5 * x, 0.0])
            .collect()
    };
    check_constants(&line(17, 0.3, 1.7), &line(29, 0.25, 0.9));
    // Circular arc, both directions.
    let coarse = arc(1.0, &angles(0.0, PI / 2.0, 13, 0.3, 2.1));
    let fine = arc(1.0, &angles(0.0, PI / 2.0, 31, 0.3, 0.7));
    check_constants(&coarse, &fine);
    check_constants(&fine, &coarse);
}

#[test]
fn constants_are_reproduced_3d() {
    check_constants(&patch(8, 0.2, 1.1, plane), &patch(13, 0.2, 0.6, plane));
    check_constants(&patch(13, 0.2, 0.6, plane), &patch(8, 0.2, 1.1, plane));
    check_constants(
        &patch(9, 0.2, 1.9, sphere_cap),
        &patch(14, 0.2, 0.4, sphere_cap),
    );
}

/// Max interpolation error of `f` from `sources` to `targets`.
fn max_error(sources: &[[f64; 3]], targets: &[[f64; 3]], f: impl Fn(&[f64; 3]) -> f64) -> f64 {
    let radii = support_radii(sources).expect("radii");
    let interp = Interpolation::new(sources, &radii, targets).expect("interpolation");
    assert!(interp.uncovered_targets().is_empty());
    let g: Vec<f64> = sources.iter().map(&f).collect();
    interp
        .apply(&g, 1)
        .expect("apply")
        .iter()
        .zip(targets)
        .map(|(v, p)| (v - f(p)).abs())
        .fold(0.0, f64::max)
}

/// Observed rates `log2(e_k / e_{k+1})` of errors at halved spacings.
fn rates(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// `n + 1` graded nodes on `[0, 1]`: the image of a uniform grid under the smooth monotone map
/// `u + a sin(2 pi u) / (2 pi)` (`|a| < 1`), so that refinement keeps the same local structure.
fn graded(n: usize, a: f64) -> Vec<f64> {
    (0..=n)
        .map(|k| {
            let u = k as f64 / n as f64;
            u + a * (2.0 * PI * u).sin() / (2.0 * PI)
        })
        .collect()
}

#[test]
fn smooth_field_converges_on_arc_2d() {
    // f as a function of arc length s = theta on the unit circle, sampled at non-matching
    // graded node sets (different gradings, spacing ratio 7/5); spacing halved 4 times.
    let f = |p: &[f64; 3]| (3.0 * p[1].atan2(p[0])).sin() + p[0] * p[0];
    let on_arc = |n: usize, a: f64| {
        let theta: Vec<f64> = graded(n, a).iter().map(|u| 0.5 * PI * u).collect();
        arc(1.0, &theta)
    };
    let errors: Vec<f64> = (0..5)
        .map(|k| {
            let n = 10 << k;
            max_error(&on_arc(n, 0.4), &on_arc((n * 7) / 5, -0.3), f)
        })
        .collect();
    let observed = rates(&errors);
    println!("arc 2D: errors {errors:?}, rates {observed:?}");
    // Measured: max errors 6.29e-2, 3.27e-2, 1.67e-2, 8.33e-3, 4.16e-3 (n = 10 .. 160 source
    // intervals); rates 0.94, 0.97, 1.00, 1.00, overall 0.98: first order, O(h), as expected with
    // radii tied to the spacing.
    assert!(errors.windows(2).all(|w| w[1] < w[0]));
    assert!(observed.iter().all(|&r| r > 0.9), "{observed:?}");
    assert!(observed[2..].iter().all(|&r| r > 0.95), "{observed:?}");
}

#[test]
fn smooth_field_converges_on_plane_3d() {
    // f(x, y) = sin(2x) cos(3y) on the plane z = 0.3, non-matching graded tensor grids
    // (spacing ratio 7/5); spacing halved 4 times (up to 81 x 81 sources).
    let f = |p: &[f64; 3]| (2.0 * p[0]).sin() * (3.0 * p[1]).cos();
    let grid = |n: usize, a: f64, b: f64| {
        let (gx, gy) = (graded(n, a), graded(n, b));
        gx.iter()
            .flat_map(|&x| gy.iter().map(move |&y| [x, y, 0.3]))
            .collect::<Vec<_>>()
    };
    let errors: Vec<f64> = (0..5)
        .map(|k| {
            let n = 5 << k;
            max_error(&grid(n, 0.4, -0.2), &grid((n * 7) / 5, -0.3, 0.3), f)
        })
        .collect();
    let observed = rates(&errors);
    println!("plane 3D: errors {errors:?}, rates {observed:?}");
    // Measured: max errors 1.82e-1, 1.13e-1, 6.50e-2, 3.23e-2, 1.61e-2 (n = 5 .. 80 source
    // intervals per side); rates 0.69, 0.80, 1.01, 1.00, overall 0.87: first order, O(h), reached
    // after a pre-asymptotic range on the coarsest grids.
    assert!(errors.windows(2).all(|w| w[1] < w[0]));
    assert!(observed.iter().all(|&r| r > 0.6), "{observed:?}");
    assert!(observed[2..].iter().all(|&r| r > 0.95), "{observed:?}");
    let overall = (errors[0] / errors[4]).log2() / 4.0;
    assert!(overall > 0.85, "overall rate {overall}");
}

#[test]
fn twice_the_spacing_interpolates_a_linear_field_better_than_algorithm_1_on_contact_meshes() {
    // The hemisphere-on-block contact surfaces refined to R/67 (the 3D Hertz test mesh): the
    // linear field x interpolated both ways between the two surfaces, at the target nodes
    // within 0.15 of the axis. Radii: Algorithm 1's (it settles at c = 0.75 here, r = 4/3 d),
    // then r = 2 d (the transfer operators' default) and r = 8/3 d, d the nearest-node distance.
    let mesh = read_msh(&common::fixture("hemisphere_on_block_hertz.msh")).unwrap();
    let sphere = ContactSurface::new(mesh.body("sphere").unwrap(), "sphere_contact").unwrap();
    let block = ContactSurface::new(mesh.body("block").unwrap(), "block_contact").unwrap();
    let h = sphere.spacing.iter().sum::<f64>() / sphere.len() as f64;
    let near = |s: &ContactSurface| -> Vec<[f64; 3]> {
        s.coords
            .iter()
            .filter(|p| p[0].hypot(p[1]) < 0.15)
            .copied()
            .collect()
    };
    let error = |from: &ContactSurface, to: &ContactSurface, radii: Vec<f64>| {
        let targets = near(to);
        let interp = Interpolation::new(&from.coords, &radii, &targets).unwrap();
        let x: Vec<f64> = from.coords.iter().map(|p| p[0]).collect();
        interp
            .apply(&x, 1)
            .expect("apply")
            .iter()
            .zip(&targets)
            .map(|(v, p)| (v - p[0]).abs() / h)
            .fold(0.0, f64::max)
    };
    let errors = |from: &ContactSurface, to: &ContactSurface| -> Vec<f64> {
        let mut e = vec![error(from, to, support_radii(&from.coords).unwrap())];
        for radius in [2.0, 8.0 / 3.0] {
            e.push(error(
                from,
                to,
                interpolation_radii(&from.coords, radius).unwrap(),
            ));
        }
        e
    };
    let (to_sphere, to_block) = (errors(&block, &sphere), errors(&sphere, &block));
    println!(
        "largest error / h, radii Algorithm 1, 2 d, 8/3 d: block to sphere {to_sphere:?}, sphere to block {to_block:?}"
    );
    // Measured: block to sphere 0.19, 0.041, 0.061; sphere to block 0.21, 0.065, 0.068.
    for e in [&to_sphere, &to_block] {
        assert!(e[0] > 0.1, "Algorithm 1's radii: {e:?}");
        assert!(e[1] < 0.5 * e[0], "{e:?}");
    }
}

/// 40 sources on an arc and 30 targets on a shifted arc, radii twice the spacing: an
/// interpolation whose `R` is dense.
fn arc_interpolation() -> (Interpolation, [usize; 2]) {
    let sources = arc(1.0, &(0..40).map(|k| 0.02 * k as f64).collect::<Vec<_>>());
    let targets = arc(
        1.0,
        &(0..30)
            .map(|k| 0.011 + 0.025 * k as f64)
            .collect::<Vec<_>>(),
    );
    let radii = interpolation_radii(&sources, 2.0).unwrap();
    let r = Interpolation::new(&sources, &radii, &targets).unwrap();
    (r, [sources.len(), targets.len()])
}

#[test]
fn sparse_rows_and_columns_are_those_of_the_dense_matrix() {
    // Sources on an arc, targets on a shifted arc: R is dense, its rows and columns computed by
    // transposed and plain solves must match it to round-off, dropping only entries <= DROP_TOL.
    let (r, [num_sources, num_targets]) = arc_interpolation();
    let dense = r.matrix().expect("matrix");
    let dense_of = |entries: &[(usize, f64)], len: usize| {
        let mut v = vec![0.0; len];
        for &(k, w) in entries {
            v[k] = w;
        }
        v
    };
    let all_targets: Vec<usize> = (0..num_targets).collect();
    for (t, row) in r.rows(&all_targets).unwrap().iter().enumerate() {
        let row = dense_of(row, num_sources);
        for (j, value) in row.iter().enumerate() {
            assert!(
                (value - dense[(t, j)]).abs() <= 1e-12 + DROP_TOL,
                "R[{t}, {j}]"
            );
        }
        assert!(
            (row.iter().sum::<f64>() - 1.0).abs() < 1e-10,
            "row {t} sums to one"
        );
    }
    let all_sources: Vec<usize> = (0..num_sources).collect();
    for (j, column) in r.columns(&all_sources).unwrap().iter().enumerate() {
        let column = dense_of(column, num_targets);
        for (t, value) in column.iter().enumerate() {
            assert!(
                (value - dense[(t, j)]).abs() <= 1e-12 + DROP_TOL,
                "R[{t}, {j}]"
            );
        }
    }
}

/// The rows and columns of `R` from the whole `Phi_MM` factored once (faer's sparse LU): the
/// reference for the patch solves. `R[t, :] = D_tt^-1 Phi_MM^-T Phi_NM[t, :]^T`, `D_tt` its sum.
fn whole_solve_rows(
    sources: &[[f64; 3]],
    radii: &[f64],
    targets: &[[f64; 3]],
    rows: &[usize],
) -> Vec<Vec<f64>> {
    use faer::linalg::solvers::Solve;
    use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
    use faer::sparse::{SparseColMat, Triplet};
    use internodes::contact::rbf::wendland_c2;
    let m = sources.len();
    let phi = |p: &[f64; 3], j: usize| {
        let d = (0..3).map(|k| (p[k] - sources[j][k]).powi(2)).sum::<f64>();
        wendland_c2(d.sqrt() / radii[j])
    };
    let mut triplets = Vec::new();
    for (i, p) in sources.iter().enumerate() {
        for j in 0..m {
            let v = phi(p, j);
            if v > 0.0 {
                triplets.push(Triplet::new(i, j, v));
            }
        }
    }
    let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &triplets).unwrap();
    let lu = Lu::try_new_with_symbolic(
        SymbolicLu::try_new(matrix.symbolic()).unwrap(),
        matrix.as_ref(),
    )
    .unwrap();
    rows.iter()
        .map(|&t| {
            let mut z: Vec<f64> = (0..m).map(|j| phi(&targets[t], j)).collect();
            lu.solve_transpose_in_place(faer::MatMut::from_column_major_slice_mut(&mut z, m, 1));
            let sum: f64 = z.iter().sum();
            z.iter().map(|v| v / sum).collect()
        })
        .collect()
}

/// An interpolation between two caps ([`on_caps`]), and every row of its `R` by the whole
/// solve.
struct Caps {
    sources: Vec<[f64; 3]>,
    targets: Vec<[f64; 3]>,
    r: Interpolation,
    whole: Vec<Vec<f64>>,
}

/// Sources on a wobbled grid of `(n_sources + 1)^2` points on a spherical cap and targets on
/// another of `(n_targets + 1)^2`, radii `radius` times the spacing.
fn on_caps(n_sources: usize, n_targets: usize, radius: f64) -> Caps {
    let sources = patch(n_sources, 0.25, 1.3, sphere_cap);
    let targets = patch(n_targets, 0.3, 0.7, sphere_cap);
    let radii = interpolation_radii(&sources, radius).unwrap();
    let r = Interpolation::new(&sources, &radii, &targets).unwrap();
    let all_rows: Vec<usize> = (0..targets.len()).collect();
    let whole = whole_solve_rows(&sources, &radii, &targets, &all_rows);
    Caps {
        sources,
        targets,
        r,
        whole,
    }
}

#[test]
fn rows_and_columns_solved_on_patches_are_those_of_the_whole_solve() {
    // 10,000 sources on a spherical cap (a wobbled grid, the transfer operators' radii: twice
    // the spacing) and 4,900 targets on another: a surface large enough that the patches
    // (rbf_patch.rs) hold a small part of it. Rows and columns in the middle of the cap,
    // computed on patches, against the whole Phi_MM's factor.
    let Caps {
        sources,
        targets,
        r,
        whole,
    } = on_caps(99, 69, 2.0);
    assert!(r.uncovered_targets().is_empty());
    let centre = sphere_cap(0.5, 0.5);
    let near = |p: &[f64; 3], reach: f64| {
        (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum::<f64>() < reach * reach
    };
    let zone: Vec<usize> = (0..targets.len())
        .filter(|&t| near(&targets[t], 0.1))
        .collect();
    let rows = r.rows(&zone).unwrap();
    // The difference at the entries a row keeps, and the largest entry it drops.
    let (mut error, mut dropped, mut reach) = (0.0f64, 0.0f64, 0.0f64);
    for (&t, row) in zone.iter().zip(&rows) {
        let mut kept = vec![None; sources.len()];
        for &(j, w) in row {
            kept[j] = Some(w);
            let d = (0..3)
                .map(|k| (sources[j][k] - targets[t][k]).powi(2))
                .sum::<f64>();
            reach = reach.max(d.sqrt());
        }
        for (a, b) in kept.iter().zip(&whole[t]) {
            match a {
                Some(a) => error = error.max((a - b).abs()),
                None => dropped = dropped.max(b.abs()),
            }
        }
    }
    let in_zone: Vec<usize> = (0..sources.len())
        .filter(|&j| near(&sources[j], 0.1))
        .collect();
    let columns = r.columns(&in_zone).unwrap();
    let (mut column_error, mut column_dropped) = (0.0f64, 0.0f64);
    for (&j, column) in in_zone.iter().zip(&columns) {
        let mut kept = vec![None; targets.len()];
        for &(t, w) in column {
            kept[t] = Some(w);
        }
        for (t, value) in kept.iter().enumerate() {
            match value {
                Some(value) => column_error = column_error.max((value - whole[t][j]).abs()),
                None => column_dropped = column_dropped.max(whole[t][j].abs()),
            }
        }
    }
    let h = 0.5 / 99.0;
    println!(
        "{} sources, {} rows and {} columns: largest difference from the whole solve {error:.1e} \
         (rows), {column_error:.1e} (columns); largest entry dropped {dropped:.1e} (rows), \
         {column_dropped:.1e} (columns); rows reach {:.1} spacings",
        sources.len(),
        zone.len(),
        in_zone.len(),
        reach / h
    );
    // The rows reach a small part of the cap (its extent is 100 spacings), so the patches
    // are smaller than the surface and this tests their truncation: the entries kept within
    // round-off of the whole solve's (PATCH_TOL's aim), those dropped at most DROP_TOL (the
    // whole solve's entries there, up to the same round-off).
    assert!(reach < 40.0 * h, "rows reach {:.1} spacings", reach / h);
    assert!(
        error < 1e-14 && column_error < 1e-14,
        "{error:e}, {column_error:e}"
    );
    assert!(dropped < DROP_TOL + 1e-14, "rows: {dropped:e}");
    assert!(
        column_dropped < DROP_TOL + 1e-14,
        "columns: {column_dropped:e}"
    );
}

#[test]
fn wide_supports_interpolate_as_the_whole_solve_does() {
    // Supports of ten spacings (the largest rbf_radius a case may set): Phi_MM is ill
    // conditioned, GMRES on it stops short of its tolerance and the whole matrix is factored
    // (rbf_patch::WholeFactor), which then serves the rows too. Both against the whole solve.
    let Caps {
        sources,
        targets,
        r,
        whole,
    } = on_caps(59, 41, 10.0);
    let all_rows: Vec<usize> = (0..targets.len()).collect();
    let g: Vec<f64> = sources
        .iter()
        .map(|p| p[0] - 2.0 * p[1] + p[2] * p[2])
        .collect();
    let applied = r.apply(&g, 1).unwrap();
    let mut apply_error = 0.0f64;
    for (t, value) in applied.iter().enumerate() {
        let reference: f64 = whole[t].iter().zip(&g).map(|(w, g)| w * g).sum();
        apply_error = apply_error.max((value - reference).abs());
    }
    let rows = r.rows(&all_rows).unwrap();
    let mut row_error = 0.0f64;
    for (row, whole) in rows.iter().zip(&whole) {
        let mut kept = vec![0.0; sources.len()];
        for &(j, w) in row {
            kept[j] = w;
        }
        for (a, b) in kept.iter().zip(whole) {
            row_error = row_error.max((a - b).abs());
        }
    }
    println!("radius 10: apply {apply_error:.1e}, rows {row_error:.1e} from the whole solve");
    assert!(
        apply_error < 1e-12 && row_error < 1e-12,
        "{apply_error:e}, {row_error:e}"
    );
}
