//! Isotropic linear elastic material and its constitutive matrices.
//!
//! Voigt notation with engineering shear strains, `eps = [exx, eyy, ezz, 2eyz, 2exz, 2exy]` in
//! 3D and `eps = [exx, eyy, 2exy]` in 2D plane strain (`ezz = 0`), so that `sigma = D eps` and
//! the strain energy density is `eps . D eps / 2`.

use nalgebra::{Matrix3, Matrix6};
use thiserror::Error;

/// Young's modulus `E` and Poisson's ratio `nu` of one body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    youngs_modulus: f64,
    poisson_ratio: f64,
}

#[derive(Debug, Error, PartialEq)]
pub enum MaterialError {
    #[error("Young's modulus must be positive and finite, got {0}")]
    YoungsModulus(f64),
    #[error(
        "Poisson's ratio must lie in (-1, 0.5) (0.5 is incompressible, which P1 elements cannot \
         represent), got {0}"
    )]
    PoissonRatio(f64),
}

impl Material {
    pub fn new(youngs_modulus: f64, poisson_ratio: f64) -> Result<Self, MaterialError> {
        if !(youngs_modulus > 0.0 && youngs_modulus.is_finite()) {
            return Err(MaterialError::YoungsModulus(youngs_modulus));
        }
        if !(poisson_ratio > -1.0 && poisson_ratio < 0.5) {
            return Err(MaterialError::PoissonRatio(poisson_ratio));
        }
        Ok(Self {
            youngs_modulus,
            poisson_ratio,
        })
    }

    pub fn youngs_modulus(&self) -> f64 {
        self.youngs_modulus
    }

    pub fn poisson_ratio(&self) -> f64 {
        self.poisson_ratio
    }

    /// Lamé parameters `(lambda, mu)`: `lambda = E nu / ((1 + nu)(1 - 2 nu))`,
    /// `mu = E / (2 (1 + nu))`.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus, self.poisson_ratio);
        (
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            e / (2.0 * (1.0 + nu)),
        )
    }

    /// Plane-strain `D` (3 x 3): `sigma = lambda tr(eps) I + 2 mu eps` restricted to `ezz = 0`.
    pub fn plane_strain_matrix(&self) -> Matrix3<f64> {
        let (l, m) = self.lame();
        Matrix3::new(l + 2.0 * m, l, 0.0, l, l + 2.0 * m, 0.0, 0.0, 0.0, m)
    }

    /// 3D `D` (6 x 6).
    pub fn elasticity_matrix_3d(&self) -> Matrix6<f64> {
        let (l, m) = self.lame();
        let mut d = Matrix6::zeros();
        for i in 0..3 {
            for j in 0..3 {
                d[(i, j)] = l;
            }
            d[(i, i)] = l + 2.0 * m;
            d[(i + 3, i + 3)] = m;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_non_physical_parameters() {
        assert_eq!(
            Material::new(0.0, 0.3),
            Err(MaterialError::YoungsModulus(0.0))
        );
        assert_eq!(
            Material::new(-1.0, 0.3),
            Err(MaterialError::YoungsModulus(-1.0))
        );
        assert!(matches!(
            Material::new(f64::NAN, 0.3),
            Err(MaterialError::YoungsModulus(_))
        ));
        assert_eq!(
            Material::new(1.0, 0.5),
            Err(MaterialError::PoissonRatio(0.5))
        );
        assert_eq!(
            Material::new(1.0, -1.0),
            Err(MaterialError::PoissonRatio(-1.0))
        );
        assert!(Material::new(1.0, -0.99).is_ok());
        assert!(Material::new(1.0, 0.499).is_ok());
    }

    #[test]
    fn uniaxial_stress_recovers_youngs_modulus() {
        // Under uniaxial stress sigma_xx = E eps_xx with lateral strains -nu eps_xx.
        let m = Material::new(210.0, 0.3).unwrap();
        let eps = nalgebra::Vector6::new(1.0, -0.3, -0.3, 0.0, 0.0, 0.0);
        let sigma = m.elasticity_matrix_3d() * eps;
        assert!((sigma[0] - 210.0).abs() < 1e-12 * 210.0);
        assert!(sigma[1].abs() < 1e-12 * 210.0 && sigma[2].abs() < 1e-12 * 210.0);
    }
}
