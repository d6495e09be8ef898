//! Where the paper's capsule model and the exact geometry disagree about contact.

use super::{ApproximationFinding, Distances};

/// Names every pair on which the exact and approximate answers (of the same world and
/// configuration) disagree about contact: [`ApproximationFinding::UnsafeApproximation`] when the
/// capsules are free but the exact geometry collides (signed distance <= 0), and
/// [`ApproximationFinding::ConservativeApproximation`] for the reverse.
///
/// A disagreement is reported only when the two distances are more than `tolerance` (m) apart, so
/// a pair touching in both models within rounding is not a finding. Findings are in pair order.
///
/// # Panics
/// When the two answers do not come from the same world (different pair lists).
pub fn compare(exact: &Distances, approx: &Distances, tolerance: f64) -> Vec<ApproximationFinding> {
    assert!(
        exact.estimates.len() == approx.estimates.len()
            && exact.estimates.iter().zip(&approx.estimates).all(|(e, a)| (e.a, e.b) == (a.a, a.b)),
        "compare answers of the same collision world"
    );
    let mut findings = Vec::new();
    for (pair, (e, a)) in exact.estimates.iter().zip(&approx.estimates).enumerate() {
        if (e.distance - a.distance).abs() <= tolerance {
            continue;
        }
        if e.distance <= 0.0 && a.distance > 0.0 {
            findings.push(ApproximationFinding::UnsafeApproximation {
                pair,
                a: e.a,
                b: e.b,
                exact_distance: e.distance,
                approximate_distance: a.distance,
            });
        } else if a.distance <= 0.0 && e.distance > 0.0 {
            findings.push(ApproximationFinding::ConservativeApproximation {
                pair,
                a: e.a,
                b: e.b,
                exact_distance: e.distance,
                exact_lower_bound: !e.exact,
                approximate_distance: a.distance,
            });
        }
    }
    findings
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::{Body, PairEstimate};

    fn answer(distances: &[(f64, bool)]) -> Distances {
        let mut answer = Distances::new();
        answer.estimates = distances
            .iter()
            .enumerate()
            .map(|(k, &(distance, exact))| PairEstimate {
                a: Body::Link(1),
                b: Body::Obstacle(k),
                distance,
                exact,
            })
            .collect();
        answer
    }

    #[test]
    fn names_unsafe_and_conservative_pairs_beyond_the_tolerance() {
        let exact = answer(&[(-0.01, true), (0.2, false), (0.5, true), (-1e-12, true)]);
        let approx = answer(&[(0.02, true), (-0.03, true), (0.4, true), (1e-12, true)]);
        let findings = compare(&exact, &approx, 1e-9);
        assert_eq!(
            findings,
            [
                ApproximationFinding::UnsafeApproximation {
                    pair: 0,
                    a: Body::Link(1),
                    b: Body::Obstacle(0),
                    exact_distance: -0.01,
                    approximate_distance: 0.02
                },
                ApproximationFinding::ConservativeApproximation {
                    pair: 1,
                    a: Body::Link(1),
                    b: Body::Obstacle(1),
                    exact_distance: 0.2,
                    exact_lower_bound: true,
                    approximate_distance: -0.03
                }
            ]
        );
    }
}
