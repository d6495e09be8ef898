//! Rigid-body statics and inertia of the chain, our own: the generalised gravity forces (what
//! each actuator must apply to hold a configuration) and the diagonal of the joint-space mass
//! matrix (the inertia each joint sees from everything beyond it). Both are the independent
//! counterparts of MuJoCo's `qfrc_bias` (at rest) and `qM`; `tests/dynamics.rs` compares them.
//!
//! Gravity acts along world -z. With `c_k` the world centre of mass of link `k`, `m_k` its mass,
//! and joint `j` an axis `a_j` through `p_j` (the child link frame, see [`Model::forward`]):
//!
//! - revolute: `G_j = sum_{k > j} m_k g (a_j x (c_k - p_j)) . z`, the derivative of the
//!   potential energy `V = sum m_k g c_k . z` with respect to `q_j`;
//! - prismatic: `G_j = (a_j . z) g sum_{k > j} m_k`.
//!
//! The diagonal of the mass matrix is the composite-rigid-body inertia about the joint axis:
//! `M_jj = a_j^T (sum_{k > j} I_k + m_k (|r_k|^2 1 - r_k r_k^T)) a_j` with `r_k = c_k - p_j`
//! (revolute), `M_jj = sum_{k > j} m_k` (prismatic). Rotor inertia (armature) is not modelled,
//! as in the MJCF export.

use super::{JointKind, KinematicsWorkspace, Model};
use nalgebra::{Matrix3, Vector3};

/// World position of a joint's axis point, its world unit axis, and whether it is prismatic.
struct JointInWorld {
    point: Vector3<f64>,
    axis: Vector3<f64>,
    prismatic: bool,
}

/// Mass, world centre of mass and world-axes inertia about the centre of mass of one link.
struct BodyInWorld {
    mass: f64,
    com: Vector3<f64>,
    inertia: Matrix3<f64>,
}

impl Model {
    /// World joint axes and link mass properties at `q`.
    fn bodies_in_world(&self, q: &[f64], ws: &mut KinematicsWorkspace) -> (Vec<JointInWorld>, Vec<BodyInWorld>) {
        self.forward(q, ws);
        let joints = self
            .joints
            .iter()
            .enumerate()
            .map(|(j, joint)| {
                // The joint frame is the child link's frame (the motion comes after the fixed
                // offset), so its origin and rotated axis are read from link j + 1.
                let frame = &ws.link_in_world[j + 1];
                JointInWorld {
                    point: frame.translation.vector,
                    axis: frame.rotation * joint.axis.into_inner(),
                    prismatic: joint.kind == JointKind::Prismatic,
                }
            })
            .collect();
        let bodies = self
            .links
            .iter()
            .zip(&ws.link_in_world)
            .map(|(link, frame)| match &link.inertial {
                Some(inertial) => {
                    let rotation = frame.rotation.to_rotation_matrix();
                    let r = rotation.matrix();
                    BodyInWorld {
                        mass: inertial.mass,
                        com: (frame * nalgebra::Point3::from(inertial.com)).coords,
                        inertia: r * inertial.inertia * r.transpose(),
                    }
                }
                // The fixed base may have no inertial; it never moves, so it adds nothing.
                None => BodyInWorld {
                    mass: 0.0,
                    com: Vector3::zeros(),
                    inertia: Matrix3::zeros(),
                },
            })
            .collect();
        (joints, bodies)
    }

    /// Generalised gravity forces at `q` (rad or m), gravity `gravity_m_s2` (m/s^2) along world
    /// -z: per joint, the torque (N m) or force (N) its actuator must apply to hold the robot at
    /// rest. Equals MuJoCo's `qfrc_bias` at zero velocity.
    ///
    /// # Panics
    /// When `q.len()` differs from [`Model::dof`].
    pub fn gravity_torques(&self, q: &[f64], gravity_m_s2: f64) -> Vec<f64> {
        self.gravity_torques_in(&mut self.workspace(), q, gravity_m_s2)
    }

    /// [`Model::gravity_torques`] in a workspace kept across calls (a workspace costs more to
    /// make than the torques, and a trajectory's static load asks at every sample).
    ///
    /// # Panics
    /// When `q.len()` differs from [`Model::dof`] or `ws` is not this model's.
    pub fn gravity_torques_in(&self, ws: &mut KinematicsWorkspace, q: &[f64], gravity_m_s2: f64) -> Vec<f64> {
        let (joints, bodies) = self.bodies_in_world(q, ws);
        let up = Vector3::z();
        // Sweep from the tip: the mass and first mass moment of everything beyond joint j
        // accumulate, so each joint costs O(1).
        let mut mass_beyond = 0.0;
        let mut moment_beyond = Vector3::zeros();
        let mut torques = vec![0.0; joints.len()];
        for j in (0..joints.len()).rev() {
            let body = &bodies[j + 1];
            mass_beyond += body.mass;
            moment_beyond += body.com * body.mass;
            let joint = &joints[j];
            torques[j] = if joint.prismatic {
                gravity_m_s2 * mass_beyond * joint.axis.dot(&up)
            } else {
                // sum m_k (a x (c_k - p)) . z = (a x (sum m_k c_k - M p)) . z
                let lever = moment_beyond - joint.point * mass_beyond;
                gravity_m_s2 * joint.axis.cross(&lever).dot(&up)
            };
        }
        torques
    }

    /// Diagonal of the joint-space mass matrix at `q` (rad or m): per joint, the inertia
    /// (kg m^2) or mass (kg) it moves, composite of every link beyond it. Equals the diagonal
    /// of MuJoCo's `qM` (no armature).
    ///
    /// # Panics
    /// When `q.len()` differs from [`Model::dof`].
    pub fn reflected_inertia(&self, q: &[f64]) -> Vec<f64> {
        let (joints, bodies) = self.bodies_in_world(q, &mut self.workspace());
        // Composite body beyond joint j, about the world origin: mass, first moment, and the
        // second moment sum (I_k + m_k (|c_k|^2 1 - c_k c_k^T)).
        let mut mass_beyond = 0.0;
        let mut moment_beyond = Vector3::zeros();
        let mut inertia_about_origin = Matrix3::zeros();
        let mut diagonal = vec![0.0; joints.len()];
        for j in (0..joints.len()).rev() {
            let body = &bodies[j + 1];
            let c = body.com;
            mass_beyond += body.mass;
            moment_beyond += c * body.mass;
            inertia_about_origin += body.inertia + body.mass * (Matrix3::identity() * c.dot(&c) - c * c.transpose());
            let joint = &joints[j];
            diagonal[j] = if joint.prismatic {
                mass_beyond
            } else {
                // Parallel-axis shift of the composite inertia from the origin to the joint
                // point p, along the axis a only (h: first mass moment, M: mass):
                // a^T I_p a = a^T I_o a - 2 [(h . p) - (a . h)(a . p)] + M [|p|^2 - (a . p)^2].
                let (a, p, h) = (joint.axis, joint.point, moment_beyond);
                let about_origin = a.dot(&(inertia_about_origin * a));
                about_origin - 2.0 * (h.dot(&p) - a.dot(&h) * a.dot(&p)) + mass_beyond * (p.dot(&p) - a.dot(&p).powi(2))
            };
        }
        diagonal
    }
}

#[cfg(test)]
mod tests {
    use crate::model::{Inertial, Joint, JointKind, Link, Model, ModelSource};
    use nalgebra::{Isometry3, Matrix3, Unit, Vector3};
    use std::f64::consts::FRAC_PI_2;

    const G: f64 = 9.81;

    fn link(name: &str, inertial: Option<Inertial>) -> Link {
        Link {
            name: name.into(),
            merged: vec![],
            colliders: vec![],
            inertial,
            segments: vec![],
        }
    }

    fn joint(name: &str, parent_from_joint: Isometry3<f64>, axis: Vector3<f64>, kind: JointKind) -> Joint {
        Joint {
            name: name.into(),
            kind,
            parent_from_joint,
            axis: Unit::new_normalize(axis),
            limits: None,
            max_velocity: None,
            max_effort: None,
        }
    }

    /// A point-like body of `mass` at `com` with a small diagonal inertia `moment`.
    fn body(mass: f64, com: Vector3<f64>, moment: f64) -> Inertial {
        Inertial {
            mass,
            com,
            inertia: Matrix3::identity() * moment,
        }
    }

    /// A planar arm in the x-z plane: joints about world y, link lengths `lengths`, each link's
    /// mass at `com_fraction` of its length.
    fn planar_arm(lengths: &[f64], masses: &[f64], moment: f64) -> Model {
        let mut joints = vec![];
        let mut links = vec![link("base", None)];
        let mut previous = 0.0;
        for (i, (&length, &mass)) in lengths.iter().zip(masses).enumerate() {
            let offset = Isometry3::translation(previous, 0.0, 0.0);
            joints.push(joint(&format!("j{i}"), offset, Vector3::y(), JointKind::Revolute));
            links.push(link(
                &format!("l{i}"),
                Some(body(mass, Vector3::new(length / 2.0, 0.0, 0.0), moment)),
            ));
            previous = length;
        }
        Model {
            name: "planar".into(),
            source: ModelSource::Design {
                mode: "free".into(),
                choices: vec![],
            },
            world_from_base: Isometry3::identity(),
            joints,
            links,
            last_from_tool: Isometry3::identity(),
            diagnostics: vec![],
        }
    }

    fn close(a: f64, b: f64, tolerance: f64) -> bool {
        (a - b).abs() <= tolerance * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn single_link_matches_the_pendulum_formula() {
        // Rotation about +y by q moves x towards -z: the com at (l/2 cos q, 0, -l/2 sin q).
        // V = -m g l/2 sin q, so G = dV/dq = -m g l/2 cos q; M = I_yy + m (l/2)^2.
        let (mass, length, moment) = (2.0, 0.6, 0.01);
        let model = planar_arm(&[length], &[mass], moment);
        for q in [0.0, 0.3, -1.2, 2.5] {
            let torque = model.gravity_torques(&[q], G)[0];
            let expected = -mass * G * length / 2.0 * q.cos();
            assert!(close(torque, expected, 1e-12), "q {q}: {torque} vs {expected}");
            let inertia = model.reflected_inertia(&[q])[0];
            let expected = moment + mass * (length / 2.0).powi(2);
            assert!(close(inertia, expected, 1e-12), "q {q}: {inertia} vs {expected}");
        }
    }

    #[test]
    fn two_link_planar_arm_matches_the_textbook() {
        // Angles measured from +x towards -z (rotation about +y). Link i has length l_i, mass
        // m_i at l_i / 2 and moment I about its com.
        let (l1, l2, m1, m2, moment) = (0.5, 0.4, 3.0, 2.0, 0.02);
        let model = planar_arm(&[l1, l2], &[m1, m2], moment);
        for (q1, q2) in [(0.0, 0.0), (0.4, -0.9), (-1.1, 2.0), (FRAC_PI_2, 0.3)] {
            let torques = model.gravity_torques(&[q1, q2], G);
            let g1 = -(m1 * l1 / 2.0 + m2 * l1) * G * q1.cos() - m2 * G * l2 / 2.0 * (q1 + q2).cos();
            let g2 = -m2 * G * l2 / 2.0 * (q1 + q2).cos();
            assert!(close(torques[0], g1, 1e-12), "{torques:?} vs {g1}");
            assert!(close(torques[1], g2, 1e-12), "{torques:?} vs {g2}");
            // M11 = I1 + I2 + m1 (l1/2)^2 + m2 (l1^2 + (l2/2)^2 + l1 l2 cos q2), M22 = I2 + m2 (l2/2)^2.
            let inertia = model.reflected_inertia(&[q1, q2]);
            let m11 = 2.0 * moment + m1 * (l1 / 2.0).powi(2) + m2 * (l1 * l1 + (l2 / 2.0).powi(2) + l1 * l2 * q2.cos());
            let m22 = moment + m2 * (l2 / 2.0).powi(2);
            assert!(close(inertia[0], m11, 1e-12), "{inertia:?} vs {m11}");
            assert!(close(inertia[1], m22, 1e-12), "{inertia:?} vs {m22}");
        }
    }

    fn potential_energy(model: &Model, q: &[f64]) -> f64 {
        let mut ws = model.workspace();
        model.forward(q, &mut ws);
        model
            .links
            .iter()
            .zip(&ws.link_in_world)
            .filter_map(|(link, frame)| {
                let inertial = link.inertial.as_ref()?;
                Some(inertial.mass * G * (frame * nalgebra::Point3::from(inertial.com)).z)
            })
            .sum()
    }

    #[test]
    fn gravity_torques_are_the_gradient_of_potential_energy() {
        let text = r#"{"mode": "modular", "modules": ["direct", "L-short", "direct", "I-short", "L-long", "I-long"]}"#;
        let design = crate::design::parse(text, std::path::Path::new("six.json")).expect("valid design");
        let mut model = crate::model::from_design(&design);
        // A tilted base and a prismatic joint exercise every branch.
        model.world_from_base = Isometry3::new(Vector3::new(0.1, -0.2, 0.3), Vector3::new(0.2, -0.4, 0.1));
        model.joints[3].kind = JointKind::Prismatic;
        let step = 1e-6;
        for q in [
            vec![0.0; 6],
            vec![0.3, -0.7, 1.1, 0.05, -2.0, 0.9],
            vec![-1.5, 0.2, -0.4, -0.1, 0.6, 2.8],
        ] {
            let torques = model.gravity_torques(&q, G);
            for j in 0..q.len() {
                let (mut plus, mut minus) = (q.clone(), q.clone());
                plus[j] += step;
                minus[j] -= step;
                let numeric = (potential_energy(&model, &plus) - potential_energy(&model, &minus)) / (2.0 * step);
                assert!(
                    (torques[j] - numeric).abs() < 1e-6,
                    "joint {j} at {q:?}: {} vs {numeric}",
                    torques[j]
                );
            }
        }
    }
}
