//! Mass properties: construction from simple solids, merging rigidly attached bodies, and the
//! physical validity checks MuJoCo and rapier rely on.

use nalgebra::{Isometry3, Matrix3, Vector3};
use serde::Serialize;

/// Relative slack on the triangle inequality of principal moments; MuJoCo accepts equality
/// (a thin rod or a flat plate) up to rounding.
const TRIANGLE_SLACK: f64 = 1e-9;

/// Largest shortfall of the triangle inequality (`(I3 - I1 - I2) / I3`) that a link's inertia is
/// balanced for, with a warning; beyond it the file is taken to be wrong (a typo, a unit slip).
/// Vendors' URDFs miss it: pybullet_data's xArm 6 by 0.75 % (`link2`) and 13.5 % (`link3`).
pub(super) const BALANCE_LIMIT: f64 = 0.25;

/// Mass, centre of mass and rotational inertia of one link, in the link frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Inertial {
    /// Mass in kg.
    pub mass: f64,
    /// Centre of mass in the link frame (m).
    pub com: Vector3<f64>,
    /// Inertia tensor about the centre of mass, link-frame axes (kg m^2).
    pub inertia: Matrix3<f64>,
}

impl Inertial {
    /// A solid cylinder along local z, centred at the origin.
    pub fn solid_cylinder(mass: f64, radius: f64, length: f64) -> Self {
        let axial = mass * radius * radius / 2.0;
        let transverse = mass * (3.0 * radius * radius + length * length) / 12.0;
        Self::diagonal(mass, [transverse, transverse, axial])
    }

    /// A thin-walled tube along local z, centred at the origin.
    pub fn thin_tube(mass: f64, radius: f64, length: f64) -> Self {
        let axial = mass * radius * radius;
        let transverse = mass * (6.0 * radius * radius + length * length) / 12.0;
        Self::diagonal(mass, [transverse, transverse, axial])
    }

    /// A solid sphere centred at the origin.
    pub fn solid_sphere(mass: f64, radius: f64) -> Self {
        let moment = 0.4 * mass * radius * radius;
        Self::diagonal(mass, [moment; 3])
    }

    fn diagonal(mass: f64, moments: [f64; 3]) -> Self {
        Self {
            mass,
            com: Vector3::zeros(),
            inertia: Matrix3::from_diagonal(&Vector3::from(moments)),
        }
    }

    /// The same body seen from a frame in which its own frame sits at `outer_from_inner`.
    pub fn transformed(&self, outer_from_inner: &Isometry3<f64>) -> Self {
        let rotation = outer_from_inner.rotation.to_rotation_matrix();
        let r = rotation.matrix();
        Self {
            mass: self.mass,
            com: (outer_from_inner * nalgebra::Point3::from(self.com)).coords,
            inertia: r * self.inertia * r.transpose(),
        }
    }

    /// Several rigidly joined bodies as one (parallel-axis theorem). `None` for an empty list or
    /// zero total mass.
    pub fn combine(parts: &[Inertial]) -> Option<Inertial> {
        let mass: f64 = parts.iter().map(|p| p.mass).sum();
        if mass <= 0.0 {
            return None;
        }
        let com = parts.iter().map(|p| p.com * p.mass).sum::<Vector3<f64>>() / mass;
        let inertia = parts
            .iter()
            .map(|p| {
                let d = p.com - com;
                p.inertia + p.mass * (Matrix3::identity() * d.dot(&d) - d * d.transpose())
            })
            .sum();
        Some(Inertial { mass, com, inertia })
    }

    /// Principal moments, ascending (kg m^2).
    pub fn principal_moments(&self) -> [f64; 3] {
        let symmetric = (self.inertia + self.inertia.transpose()) / 2.0;
        let mut moments: Vec<f64> = symmetric.symmetric_eigenvalues().iter().copied().collect();
        moments.sort_by(f64::total_cmp);
        [moments[0], moments[1], moments[2]]
    }

    /// How far the principal moments fall short of the triangle inequality, relative to the
    /// largest (`(I3 - I1 - I2) / I3`; negative when it holds); NaN when something else is
    /// wrong (see [`Self::check`]).
    pub fn triangle_shortfall(&self) -> f64 {
        match self.principal_if_definite() {
            Ok([a, b, c]) => (c - a - b) / c,
            Err(_) => f64::NAN,
        }
    }

    /// These mass properties with the two smaller principal moments each raised by half the
    /// triangle inequality's shortfall (the least change that meets it, about the same principal
    /// axes), and that shortfall relative to the largest moment; `None` unless the inequality is
    /// all [`Self::check`] finds wrong and it falls short by at most 25 % of the largest moment.
    pub fn balanced(&self) -> Option<(Inertial, f64)> {
        // NaN (something else wrong) fails the range test too.
        let shortfall = self.triangle_shortfall();
        if !(shortfall > 0.0 && shortfall <= BALANCE_LIMIT) || self.check().is_ok() {
            return None;
        }
        let eigen = ((self.inertia + self.inertia.transpose()) / 2.0).symmetric_eigen();
        // Raised a little past equality, so the check's rounding slack is not relied on.
        let [a, b, c] = self.principal_moments();
        let raise = (c - a - b) * (0.5 + TRIANGLE_SLACK);
        let largest = eigen.eigenvalues.imax();
        let moments = Vector3::from_fn(|k, _| eigen.eigenvalues[k] + if k == largest { 0.0 } else { raise });
        let inertia = eigen.eigenvectors * Matrix3::from_diagonal(&moments) * eigen.eigenvectors.transpose();
        let fixed = Inertial {
            inertia: (inertia + inertia.transpose()) / 2.0,
            ..self.clone()
        };
        fixed.check().is_ok().then_some((fixed, shortfall))
    }

    /// Why these mass properties are not physical, if they are not: non-positive or non-finite
    /// mass, a tensor that is not symmetric positive definite, or principal moments that break
    /// the triangle inequality (`I1 + I2 >= I3`).
    pub fn check(&self) -> Result<(), String> {
        let [a, b, c] = self.principal_if_definite()?;
        if a + b < c * (1.0 - TRIANGLE_SLACK) {
            return Err(format!(
                "principal moments {a:.3e} + {b:.3e} < {c:.3e} kg m^2 break the triangle inequality"
            ));
        }
        Ok(())
    }

    /// The principal moments, ascending, when the mass is positive, everything finite and the
    /// tensor symmetric positive definite (the eigenvalues are only computed then: a NaN
    /// tensor never reaches the iteration); else why not.
    fn principal_if_definite(&self) -> Result<[f64; 3], String> {
        if !(self.mass.is_finite() && self.mass > 0.0) {
            return Err(format!("mass {} kg is not positive", self.mass));
        }
        if self.com.iter().chain(self.inertia.iter()).any(|v| !v.is_finite()) {
            return Err("centre of mass or inertia is not finite".into());
        }
        let asymmetry = (self.inertia - self.inertia.transpose()).abs().max();
        if asymmetry > 1e-12 * self.inertia.abs().max().max(1e-12) {
            return Err("inertia tensor is not symmetric".into());
        }
        let [a, b, c] = self.principal_moments();
        if a <= 0.0 {
            return Err(format!(
                "inertia is not positive definite (principal moments {a:.3e}, {b:.3e}, {c:.3e} kg m^2)"
            ));
        }
        Ok([a, b, c])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn an_inertia_just_short_of_the_triangle_inequality_is_balanced_by_the_least_change() {
        // The xArm 6's link2 (pybullet_data's xarm6_robot.urdf), turned off its principal axes.
        let turn = UnitQuaternion::from_euler_angles(0.3, -0.2, 0.7).to_rotation_matrix().into_inner();
        let inertial = Inertial {
            mass: 1.7,
            com: Vector3::zeros(),
            inertia: turn * Matrix3::from_diagonal(&Vector3::new(3.058e-3, 2.364e-2, 2.690e-2)) * turn.transpose(),
        };
        assert!(inertial.check().unwrap_err().contains("triangle"));
        let (fixed, shortfall) = inertial.balanced().expect("0.75 % short: balanced");
        assert!((shortfall - 0.0072).abs() < 1e-3, "{shortfall}");
        assert!(fixed.check().is_ok());
        let [a, b, c] = fixed.principal_moments();
        assert!((a + b - c).abs() < 1e-9 && (c - 2.690e-2).abs() < 1e-12, "{a} {b} {c}");
        // The same principal axes: the largest moment's axis is unchanged.
        let axis = turn * Vector3::z();
        assert!(((fixed.inertia * axis).normalize() - axis).norm() < 1e-9);
        // A gross error (the test fixture's 0.01 + 0.01 < 0.5) stays an error.
        let gross = Inertial::diagonal(1.0, [0.01, 0.01, 0.5]);
        assert!(gross.balanced().is_none());
        assert!(Inertial::diagonal(1.0, [0.2, 0.3, 0.4]).balanced().is_none());
        // Other faults are not balanced, and a NaN tensor never reaches the eigenvalues.
        let nan = Inertial::diagonal(1.0, [f64::NAN, 0.01, 0.019]);
        assert!(nan.triangle_shortfall().is_nan() && nan.balanced().is_none());
        assert!(Inertial::diagonal(-1.0, [0.01, 0.01, 0.019]).balanced().is_none());
    }

    #[test]
    fn two_point_like_spheres_combine_by_parallel_axis() {
        let a = Inertial::solid_sphere(1.0, 1e-3).transformed(&Isometry3::translation(1.0, 0.0, 0.0));
        let b = Inertial::solid_sphere(1.0, 1e-3).transformed(&Isometry3::translation(-1.0, 0.0, 0.0));
        let both = Inertial::combine(&[a, b]).expect("positive mass");
        assert!(both.com.norm() < 1e-15);
        // Two unit masses at +-1 m on x: Iyy = Izz = 2 kg m^2 (plus the tiny spheres).
        assert!((both.inertia[(1, 1)] - 2.0).abs() < 1e-5);
        assert!(both.inertia[(0, 0)] < 1e-5);
    }

    #[test]
    fn rotation_preserves_principal_moments() {
        let body = Inertial::solid_cylinder(2.0, 0.06, 0.5);
        let pose = Isometry3::from_parts(Translation3::new(0.1, 0.2, 0.3), UnitQuaternion::from_euler_angles(0.3, 0.9, -0.4));
        let moved = body.transformed(&pose);
        let (p, q) = (body.principal_moments(), moved.principal_moments());
        for k in 0..3 {
            assert!((p[k] - q[k]).abs() < 1e-12, "{p:?} {q:?}");
        }
        assert!(moved.check().is_ok());
    }

    #[test]
    fn rejects_triangle_inequality_violation() {
        let bad = Inertial {
            mass: 1.0,
            com: Vector3::zeros(),
            inertia: Matrix3::from_diagonal(&Vector3::new(0.1, 0.1, 0.3)),
        };
        assert!(bad.check().unwrap_err().contains("triangle"));
    }

    #[test]
    fn rejects_zero_mass() {
        let zero = Inertial {
            mass: 0.0,
            com: Vector3::zeros(),
            inertia: Matrix3::identity(),
        };
        assert!(zero.check().unwrap_err().contains("mass"));
    }
}
