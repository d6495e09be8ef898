//! Which moving parts of a robot tree are the arm, one rule for URDF and MJCF input: the
//! gripper joints (they end the tree, and a coupling the file declares, a gripper word in the
//! joint's own name, a sibling that also ends the tree, or a slide whose part is named with a
//! gripper word marks them), and the arm as the longest chain of the other moving parts. A
//! part's name alone never takes a turning joint off the arm: a wrist whose link is called
//! `gripper` stays a wrist ([`named_but_kept`]). The loaders describe their trees as [`Mover`]s
//! and say the results in their own terms.

use super::names;
use std::collections::BTreeMap;

/// One moving part of the tree: a movable URDF joint with its child link, an MJCF body with its
/// joints. Movers are listed parents first.
pub(super) struct Mover {
    /// The mover it hangs from (an index into the list); `None`: the base's body.
    pub(super) above: Option<usize>,
    /// Its joints' names.
    pub(super) joints: Vec<String>,
    /// Its link's or body's name.
    pub(super) part: String,
    /// Couplings the file declares (a URDF `<mimic>`, an MJCF `<equality joint>`), each with
    /// the mover at its other end (`None`: it marks this mover whatever is there) and the
    /// sentence that says it.
    pub(super) couplings: Vec<(Option<usize>, String)>,
    /// Every joint slides (URDF `prismatic`, MJCF `slide`): a finger's motion.
    pub(super) slides: bool,
}

/// Why a mover is a gripper's, first reason that holds in this order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum GripperReason {
    /// Couplings with a mover not below it (or none), their sentences joined.
    Coupled(String),
    /// A joint's own name has this gripper word (`jointGripper`: the joint says what it is).
    JointWord(&'static str),
    /// It slides and its link or body is named with this gripper word.
    PartWord(&'static str),
    /// It and `other` hang from the mover `above` and nothing moves below either (two fingers
    /// on a hand); never from the base's body (two arms on one torso are arms).
    Sibling {
        /// The other finger.
        other: usize,
        /// The hand.
        above: usize,
    },
}

/// Whether mover `mover` hangs, at any depth, below mover `ancestor`.
fn is_below(movers: &[Mover], mover: usize, ancestor: usize) -> bool {
    let mut at = movers[mover].above;
    while let Some(m) = at {
        if m == ancestor {
            return true;
        }
        at = movers[m].above;
    }
    false
}

/// Whether every mover hanging directly from `mover` is one of `grippers` (nothing else moves
/// below it).
fn ends_tree(movers: &[Mover], mover: usize, grippers: &BTreeMap<usize, GripperReason>) -> bool {
    (0..movers.len())
        .filter(|&below| movers[below].above == Some(mover))
        .all(|below| grippers.contains_key(&below))
}

/// Movers in a chain from the base down to `mover`, itself included.
fn depth(movers: &[Mover], mover: usize) -> usize {
    1 + std::iter::successors(movers[mover].above, |&m| movers[m].above).count()
}

/// The movers that belong to a gripper, with the reason. A mover qualifies when every mover
/// below it is a gripper's (it ends the tree) and a [`GripperReason`] holds. A tree that would
/// be all gripper (a gripper on its own) has none: its joints are the chain.
pub(super) fn grippers(movers: &[Mover]) -> BTreeMap<usize, GripperReason> {
    let depths: Vec<usize> = (0..movers.len()).map(|m| depth(movers, m)).collect();
    let deepest = depths.iter().copied().max().unwrap_or(0);
    let mut grippers: BTreeMap<usize, GripperReason> = BTreeMap::new();
    // Deepest first: whether a mover ends the tree depends on the movers below it, and
    // siblings share a depth.
    for level in (1..=deepest).rev() {
        let at_level: Vec<usize> = (0..movers.len()).filter(|&m| depths[m] == level).collect();
        let trailing: BTreeMap<usize, bool> = at_level.iter().map(|&m| (m, ends_tree(movers, m, &grippers))).collect();
        for &m in &at_level {
            if !trailing[&m] {
                continue;
            }
            let mover = &movers[m];
            let coupled: Vec<&str> = mover
                .couplings
                .iter()
                .filter(|(partner, _)| partner.is_none_or(|p| p != m && !is_below(movers, p, m)))
                .map(|(_, sentence)| sentence.as_str())
                .collect();
            let sibling = mover.above.and_then(|above| {
                at_level
                    .iter()
                    .copied()
                    .find(|&other| other != m && movers[other].above == Some(above) && trailing[&other])
                    .map(|other| GripperReason::Sibling { other, above })
            });
            let reason = if !coupled.is_empty() {
                Some(GripperReason::Coupled(coupled.join("; ")))
            } else if let Some(word) = mover.joints.iter().find_map(|j| names::gripper_word(j)) {
                Some(GripperReason::JointWord(word))
            } else if let Some(word) = names::gripper_word(&mover.part).filter(|_| mover.slides) {
                Some(GripperReason::PartWord(word))
            } else {
                sibling
            };
            if let Some(reason) = reason {
                grippers.insert(m, reason);
            }
        }
    }
    if grippers.len() == movers.len() {
        grippers.clear();
    }
    grippers
}

/// The movers that end the tree and whose part is named with a gripper word, yet are kept on the
/// arm because nothing else marks them (they turn, their joints' names have no gripper word, no
/// coupling, no finger beside them), with the word: what a loader says, so that a user whose
/// gripper joint this really is can end the arm above it.
pub(super) fn named_but_kept(movers: &[Mover], grippers: &BTreeMap<usize, GripperReason>) -> Vec<(usize, &'static str)> {
    (0..movers.len())
        .filter(|m| !grippers.contains_key(m))
        .filter(|&m| ends_tree(movers, m, grippers))
        .filter_map(|m| {
            let mover = &movers[m];
            names::gripper_word(&mover.part).map(|word| (m, word))
        })
        .collect()
}

/// Why no single arm end was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum NoArmEnd {
    /// Nothing but gripper joints moves (or nothing moves).
    Nothing,
    /// Chains of `length` movers end at each of `ends` (mover order).
    Tie {
        /// The chains' ends.
        ends: Vec<usize>,
        /// Their length.
        length: usize,
    },
}

/// The end of the arm, the longest chain of movers that are not `grippers`', and its length.
///
/// # Errors
/// [`NoArmEnd`] when nothing else moves or the longest chains tie.
pub(super) fn arm_end(movers: &[Mover], grippers: &BTreeMap<usize, GripperReason>) -> Result<(usize, usize), NoArmEnd> {
    let arm: Vec<(usize, usize)> = (0..movers.len())
        .filter(|m| !grippers.contains_key(m))
        .map(|m| (m, depth(movers, m)))
        .collect();
    let length = arm.iter().map(|&(_, d)| d).max().ok_or(NoArmEnd::Nothing)?;
    let ends: Vec<usize> = arm.iter().filter(|&&(_, d)| d == length).map(|&(m, _)| m).collect();
    match ends.as_slice() {
        [one] => Ok((*one, length)),
        _ => Err(NoArmEnd::Tie { ends, length }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mover(above: Option<usize>, joint: &str, part: &str) -> Mover {
        Mover {
            above,
            joints: vec![joint.into()],
            part: part.into(),
            couplings: vec![],
            slides: false,
        }
    }

    #[test]
    fn fingers_end_the_tree_and_the_arm_is_the_longest_other_chain() {
        // base - j1 - j2 - j3 - {a, b} (two plain fingers), and j1 - c (a sliding link named
        // `claw`).
        let mut movers = vec![
            mover(None, "j1", "l1"),
            mover(Some(0), "j2", "l2"),
            mover(Some(1), "j3", "l3"),
            mover(Some(2), "a", "pa"),
            mover(Some(2), "b", "pb"),
            mover(Some(0), "c", "claw_link"),
        ];
        movers[5].slides = true;
        let found = grippers(&movers);
        assert_eq!(found.get(&3), Some(&GripperReason::Sibling { other: 4, above: 2 }));
        assert_eq!(found.get(&4), Some(&GripperReason::Sibling { other: 3, above: 2 }));
        assert_eq!(found.get(&5), Some(&GripperReason::PartWord("claw")));
        assert_eq!(arm_end(&movers, &found), Ok((2, 3)));
        // A coupling to a mover below it is a linkage of the arm, not a finger pair; one to a
        // mover elsewhere marks it first.
        movers[5].couplings = vec![(Some(0), "coupled to j1".into())];
        assert_eq!(grippers(&movers).get(&5), Some(&GripperReason::Coupled("coupled to j1".into())));
        movers[2].couplings = vec![(Some(3), "coupled below".into())];
        assert!(!grippers(&movers).contains_key(&2));
    }

    #[test]
    fn two_arms_from_the_base_tie_and_a_lone_gripper_is_its_own_chain() {
        let movers = vec![mover(None, "left", "l"), mover(None, "right", "r")];
        let found = grippers(&movers);
        assert!(found.is_empty(), "{found:?}");
        assert_eq!(
            arm_end(&movers, &found),
            Err(NoArmEnd::Tie {
                ends: vec![0, 1],
                length: 1
            })
        );
        let lone = vec![mover(None, "finger_joint", "finger")];
        assert!(grippers(&lone).is_empty());
        assert_eq!(arm_end(&[], &BTreeMap::new()), Err(NoArmEnd::Nothing));
    }

    #[test]
    fn a_turning_wrist_whose_link_is_called_gripper_stays_on_the_arm() {
        // base - j1 - j2 - wrist (link `gripper`) - {f1, f2} (sliding fingers).
        let mut movers = vec![
            mover(None, "j1", "l1"),
            mover(Some(0), "j2", "l2"),
            mover(Some(1), "wrist", "gripper"),
            mover(Some(2), "f1", "left_finger"),
            mover(Some(2), "f2", "right_finger"),
        ];
        movers[3].slides = true;
        movers[4].slides = true;
        let found = grippers(&movers);
        assert_eq!(found.keys().copied().collect::<Vec<_>>(), [3, 4]);
        assert_eq!(arm_end(&movers, &found), Ok((2, 3)));
        assert_eq!(named_but_kept(&movers, &found), [(2, "gripper")]);
        // Without its fingers, the same: a part's name alone does not take a turning joint; the
        // joint's own name does.
        movers.truncate(3);
        let found = grippers(&movers);
        assert!(found.is_empty(), "{found:?}");
        assert_eq!(arm_end(&movers, &found), Ok((2, 3)));
        movers[2].joints = vec!["jointGripper".into()];
        assert_eq!(grippers(&movers).get(&2), Some(&GripperReason::JointWord("gripper")));
    }
}
