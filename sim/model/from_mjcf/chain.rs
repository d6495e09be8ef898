//! Which moving bodies of an MJCF are the arm, and where its tool frame is.
//!
//! With `--tip NAME` (a body, else a site), the chain is the moving bodies above that body. By
//! default, the arm is the longest chain of moving bodies whose joints are not gripper joints (a
//! tie is an error naming where the chains part); gripper joints follow the rule URDF input follows
//! (`model::arm`): they end the tree, and are coupled by an `<equality joint>` to a joint not
//! below them, carry a gripper word, or branch as a pair from one moving body. The tool frame is the site
//! named [`TOOL_SITE`](super::TOOL_SITE) when there is one, else the body or site rigidly below
//! the arm's last body named like a tool frame, else the last body's frame. Moving bodies off the
//! chain are held at their joints' reference position, like jointless bodies.

use super::Reader;
use crate::model::{arm, names, ModelError};
use mujoco_rs::mujoco_c::{mjtEq, mjtJoint};
use mujoco_rs::prelude::*;
use std::collections::BTreeMap;

/// Where the tool frame is.
#[derive(Debug, Clone, Copy)]
pub(in crate::model) enum Tool {
    /// The last chain body's frame.
    LastBody,
    /// A body's frame (the last chain body or a jointless body below it).
    Body(usize),
    /// A site's frame.
    Site(usize),
}

impl Reader<'_> {
    /// The nearest body above `body` that has a joint; 0 (the world) when none.
    fn moving_parent(&self, body: usize) -> usize {
        let mj = self.mj;
        let mut at = mj.body_parentid()[body] as usize;
        while at != 0 && mj.body_jntnum()[at] == 0 {
            at = mj.body_parentid()[at] as usize;
        }
        at
    }

    /// The moving bodies from the top down to `body` (included when it moves).
    fn moving_chain(&self, body: usize) -> Vec<usize> {
        let mut chain = Vec::new();
        let mut at = if self.mj.body_jntnum()[body] > 0 {
            body
        } else {
            self.moving_parent(body)
        };
        while at != 0 {
            chain.push(at);
            at = self.moving_parent(at);
        }
        chain.reverse();
        chain
    }

    fn is_below(&self, body: usize, ancestor: usize) -> bool {
        let mut at = body;
        while at != 0 {
            at = self.mj.body_parentid()[at] as usize;
            if at == ancestor {
                return true;
            }
        }
        false
    }

    fn joint_names(&self, body: usize) -> Vec<String> {
        let first = self.mj.body_jntadr()[body] as usize;
        (first..first + self.mj.body_jntnum()[body] as usize)
            .map(|j| self.name(MjtObjBase::mjOBJ_JOINT, j))
            .collect()
    }

    /// The chain to the body or site `name` (`--tip`), and its tool frame.
    ///
    /// # Errors
    /// [`ModelError::UnsupportedMjcf`] when no body or site has that name, or no joint moves it.
    pub(super) fn chain_to(&self, name: &str, choices: &mut Vec<String>) -> Result<(Vec<usize>, Tool), ModelError> {
        let mj = self.mj;
        let (body, tool) = if let Some(body) = mj.name_to_id(MjtObjBase::mjOBJ_BODY, name).filter(|&b| b != 0) {
            (body, Tool::Body(body))
        } else if let Some(site) = mj.name_to_id(MjtObjBase::mjOBJ_SITE, name) {
            (mj.site_bodyid()[site] as usize, Tool::Site(site))
        } else {
            let list = |kind: MjtObjBase, count: usize, skip: usize| {
                (skip..count)
                    .map(|i| format!("`{}`", self.name(kind, i)))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            return Err(self.unsupported(
                "--tip".into(),
                format!(
                    "no body or site named `{name}` (bodies: {}; sites: {})",
                    list(MjtObjBase::mjOBJ_BODY, mj.ffi().nbody as usize, 1),
                    list(MjtObjBase::mjOBJ_SITE, mj.ffi().nsite as usize, 0)
                ),
            ));
        };
        let chain = self.moving_chain(body);
        if chain.is_empty() {
            return Err(self.unsupported(
                format!("--tip `{name}`"),
                format!("no joint moves {}: the chain to it has no joint", self.body(body)),
            ));
        }
        self.off_chain(&chain, &BTreeMap::new(), choices);
        Ok((chain, tool))
    }

    /// The default arm and tool frame, each choice said in `choices`.
    ///
    /// # Errors
    /// [`ModelError::UnsupportedMjcf`] when the longest chains tie.
    pub(super) fn default_chain(&self, all_moving: &[usize], choices: &mut Vec<String>) -> Result<(Vec<usize>, Tool), ModelError> {
        let mj = self.mj;
        let movers = self.movers(all_moving);
        let found = arm::grippers(&movers);
        let grippers = self.gripper_bodies(all_moving, &found);
        for (body, reason) in &grippers {
            choices.push(format!(
                "joint `{}` of {} is a gripper joint, not an arm joint: {reason}; it is held at its reference position and its body is rigid geometry of the link it hangs from",
                self.joint_names(*body).join("`, `"),
                self.body(*body)
            ));
        }
        for (m, word) in arm::named_but_kept(&movers, &found) {
            choices.push(format!(
                "joint `{}` of {} is named like a gripper's (`{word}`) but kept as an arm joint: it turns, its own name has no gripper word, no equality couples it and no finger hangs beside it; if it is the gripper's, end the arm above it with --tip",
                self.joint_names(all_moving[m]).join("`, `"),
                self.body(all_moving[m])
            ));
        }
        let arm_end = match arm::arm_end(&movers, &found) {
            Ok((end, _)) => all_moving[end],
            Err(arm::NoArmEnd::Nothing) => {
                return Err(self.unsupported("<worldbody>".into(), "has no hinge or slide joint: nothing moves".into()))
            }
            Err(arm::NoArmEnd::Tie { ends, length }) => {
                let ends: Vec<usize> = ends.iter().map(|&m| all_moving[m]).collect();
                let (a, b) = (ends[0], ends[1]);
                // Name where the first two chains part: their lowest common ancestor.
                let mut fork = mj.body_parentid()[b] as usize;
                while fork != 0 && !self.is_below(a, fork) {
                    fork = mj.body_parentid()[fork] as usize;
                }
                let names: Vec<String> = ends
                    .iter()
                    .map(|&e| format!("`{}`", self.name(MjtObjBase::mjOBJ_BODY, e)))
                    .collect();
                return Err(self.unsupported(
                    self.body(b),
                    format!(
                        "is not below {}, the end of another chain of {length} moving bodies: the moving bodies branch at {} into chains that tie (ending at {}); choose the chain's end with --tip (a body or a site)",
                        self.body(a),
                        self.body(fork),
                        names.join(", ")
                    ),
                ));
            }
        };
        let chain = self.moving_chain(arm_end);
        self.off_chain(&chain, &grippers, choices);
        let arm = format!(
            "the arm is the longest chain of moving bodies whose joints are not gripper joints ({} joints, to {})",
            chain.len(),
            self.body(arm_end)
        );
        if let Some(site) = mj.name_to_id(MjtObjBase::mjOBJ_SITE, super::TOOL_SITE) {
            choices.push(format!(
                "tool frame: site `{}` (no --tip; the site named so marks the tool frame); {arm}",
                super::TOOL_SITE
            ));
            return Ok((chain, Tool::Site(site)));
        }

        // Bodies rigidly below the arm's end, and their sites.
        let body_count = mj.ffi().nbody as usize;
        let rigid: Vec<usize> = (0..body_count)
            .filter(|&b| b == arm_end || (mj.body_jntnum()[b] == 0 && self.moving_parent(b) == arm_end))
            .collect();
        let mut named: Vec<(String, Tool)> = rigid
            .iter()
            .map(|&b| (self.name(MjtObjBase::mjOBJ_BODY, b), Tool::Body(b)))
            .collect();
        for site in 0..mj.ffi().nsite as usize {
            if rigid.contains(&(mj.site_bodyid()[site] as usize)) {
                named.push((self.name(MjtObjBase::mjOBJ_SITE, site), Tool::Site(site)));
            }
        }
        let candidates: Vec<&str> = named.iter().map(|(n, _)| n.as_str()).collect();
        let what = |tool: Tool| match tool {
            Tool::Site(site) => format!("site `{}`", self.name(MjtObjBase::mjOBJ_SITE, site)),
            Tool::Body(body) => self.body(body),
            Tool::LastBody => self.body(arm_end),
        };
        let tool = match names::pick_tool(&candidates) {
            Ok(Some(name)) => {
                let tool = named.iter().find(|(n, _)| n == name).map_or(Tool::LastBody, |(_, t)| *t);
                choices.push(format!(
                    "tool frame: {} (no --tip): {arm}; it is rigidly on the arm's end and named like a tool frame ({})",
                    what(tool),
                    names::tool_rule()
                ));
                tool
            }
            Ok(None) => {
                choices.push(format!(
                    "tool frame: the frame of {} (no --tip): {arm}; no body or site rigidly on it is named like a tool frame ({})",
                    self.body(arm_end),
                    names::tool_rule()
                ));
                Tool::LastBody
            }
            Err(tied) => {
                choices.push(format!(
                    "tool frame: the frame of {} (no --tip): {arm}; the bodies and sites on it named like a tool frame tie ({}): choose one with --tip",
                    self.body(arm_end),
                    tied.join(", ")
                ));
                Tool::LastBody
            }
        };
        Ok((chain, tool))
    }

    /// Says which moving bodies, other than gripper ones, the chain leaves out.
    fn off_chain(&self, chain: &[usize], grippers: &BTreeMap<usize, String>, choices: &mut Vec<String>) {
        let mj = self.mj;
        for body in 1..mj.ffi().nbody as usize {
            if mj.body_jntnum()[body] == 0 || chain.contains(&body) || grippers.contains_key(&body) {
                continue;
            }
            choices.push(format!(
                "joint `{}` of {} is not on the chain; it is held at its reference position",
                self.joint_names(body).join("`, `"),
                self.body(body)
            ));
        }
    }

    /// The moving bodies as [`arm::Mover`]s, in `all_moving`'s order; an `<equality joint>`
    /// couples a body to the body of the joint at its other end.
    fn movers(&self, all_moving: &[usize]) -> Vec<arm::Mover> {
        let mj = self.mj;
        let index: BTreeMap<usize, usize> = all_moving.iter().enumerate().map(|(k, &b)| (b, k)).collect();
        // Joints coupled by an <equality joint>, both ways.
        let mut coupled: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for eq in 0..mj.ffi().neq as usize {
            if mj.eq_type()[eq] != mjtEq::mjEQ_JOINT {
                continue;
            }
            let (a, b) = (mj.eq_obj1id()[eq], mj.eq_obj2id()[eq]);
            if let (Ok(a), Ok(b)) = (usize::try_from(a), usize::try_from(b)) {
                coupled.entry(a).or_default().push(b);
                coupled.entry(b).or_default().push(a);
            }
        }
        all_moving
            .iter()
            .map(|&body| {
                let first = mj.body_jntadr()[body] as usize;
                let joints = first..first + mj.body_jntnum()[body] as usize;
                let couplings = joints
                    .clone()
                    .flat_map(|j| coupled.get(&j).into_iter().flatten().copied())
                    .filter_map(|other| {
                        let partner = index.get(&(mj.jnt_bodyid()[other] as usize)).copied()?;
                        let sentence = format!(
                            "an <equality joint> couples it to joint `{}`",
                            self.name(MjtObjBase::mjOBJ_JOINT, other)
                        );
                        Some((Some(partner), sentence))
                    })
                    .collect();
                arm::Mover {
                    above: index.get(&self.moving_parent(body)).copied(),
                    slides: joints.clone().all(|j| mj.jnt_type()[j] == mjtJoint::mjJNT_SLIDE),
                    joints: joints.map(|j| self.name(MjtObjBase::mjOBJ_JOINT, j)).collect(),
                    part: self.name(MjtObjBase::mjOBJ_BODY, body),
                    couplings,
                }
            })
            .collect()
    }

    /// The gripper bodies among `found` (by body), each with the sentence that says why.
    fn gripper_bodies(&self, all_moving: &[usize], found: &BTreeMap<usize, arm::GripperReason>) -> BTreeMap<usize, String> {
        found
            .iter()
            .map(|(&m, reason)| {
                let sentence = match reason {
                    arm::GripperReason::Coupled(sentence) => sentence.clone(),
                    arm::GripperReason::JointWord(word) => format!("its name has `{word}`"),
                    arm::GripperReason::PartWord(word) => format!("its body is named like a gripper part (`{word}`)"),
                    arm::GripperReason::Sibling { other, above } => format!(
                        "it and {} branch from {} and nothing moves below them (fingers)",
                        self.body(all_moving[*other]),
                        self.body(all_moving[*above])
                    ),
                };
                (all_moving[m], sentence)
            })
            .collect()
    }
}
