//! Naming conventions of real robot descriptions that pick defaults: which frame below an arm's
//! last link is the tool frame the authors meant, and which joints belong to a gripper rather
//! than to the arm. URDF and MJCF input share them so that one robot gets the same defaults in
//! either format.

/// Tool-frame names, most specific first, as the rank [`tool_rank`] gives and messages print.
/// A TCP is the point a gripper's authors mean; `tool0` (ROS-Industrial) and `tool_frame`
/// (Kinova) are the mounting flange's tool frame; end-effector, flange and hand frames come
/// after, since a TCP or tool frame usually hangs below them.
pub(super) const TOOL_NAMES: [&str; 6] = [
    "`tcp` (`*_tcp`, `pinch`, `grip_site`)",
    "`tool0` (`tool`, `tool_frame`)",
    "`eef` (`*_eef`, `*end_effector*`)",
    "`ee_link` (`ee`)",
    "`flange` (`*_flange`, `attachment_site`)",
    "`hand` (`*_hand`)",
];

/// The rank of a tool-frame name in [`TOOL_NAMES`] (0 is the most specific), `None` for a name
/// that is not one. The name's last word decides (a trailing `link`, `frame` or `site` is
/// skipped), so `panda_hand_tcp` is a TCP, `hand_camera` is not a hand. MuJoCo Menagerie and
/// robosuite name their TCP sites `pinch` and `grip_site`, their flange sites `attachment_site`.
pub(super) fn tool_rank(name: &str) -> Option<usize> {
    let lower = name
        .to_ascii_lowercase()
        .replace("end_effector", "eef")
        .replace("endeffector", "eef");
    let words: Vec<&str> = lower
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .collect();
    let key = match words.as_slice() {
        [.., key, "link" | "frame" | "site"] => *key,
        [.., key] => *key,
        [] => return None,
    };
    match key {
        "tcp" | "pinch" | "grip" => Some(0),
        "tool0" | "tool" => Some(1),
        "eef" => Some(2),
        "ee" => Some(3),
        "flange" | "attachment" => Some(4),
        "hand" => Some(5),
        _ => None,
    }
}

/// Words that mark a joint or its moving part as a gripper's (matched inside words, any case).
pub(super) const GRIPPER_WORDS: [&str; 4] = ["finger", "gripper", "jaw", "claw"];

/// The gripper word in `name`, if any.
pub(super) fn gripper_word(name: &str) -> Option<&'static str> {
    let lower = name.to_ascii_lowercase();
    GRIPPER_WORDS.iter().copied().find(|word| lower.contains(word))
}

/// Among named candidates, the tool frame: the best-ranked name when exactly one candidate has
/// that rank. `Err` lists the candidates that tie at the best rank.
pub(super) fn pick_tool<'a>(candidates: &[&'a str]) -> Result<Option<&'a str>, Vec<&'a str>> {
    let ranked: Vec<(usize, &str)> = candidates.iter().filter_map(|n| tool_rank(n).map(|r| (r, *n))).collect();
    let Some(best) = ranked.iter().map(|(r, _)| *r).min() else {
        return Ok(None);
    };
    let top: Vec<&str> = ranked.iter().filter(|(r, _)| *r == best).map(|(_, n)| *n).collect();
    match top.as_slice() {
        [one] => Ok(Some(*one)),
        _ => Err(top),
    }
}

/// The rule as one phrase for messages.
pub(super) fn tool_rule() -> String {
    format!("tool-frame names, first match wins: {}", TOOL_NAMES.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tool_names_of_real_robots_rank_as_documented() {
        for (name, rank) in [
            ("panda_hand_tcp", Some(0)),
            ("tcp", Some(0)),
            ("link_tcp", Some(0)),
            ("tool0", Some(1)),
            ("left_tool0", Some(1)),
            ("tool_frame", Some(1)),
            ("link_eef", Some(2)),
            ("end_effector_link", Some(2)),
            ("j2n6s300_end_effector", Some(2)),
            ("ee_link", Some(3)),
            ("flange", Some(4)),
            ("attachment_site", Some(4)),
            ("pinch", Some(0)),
            ("grip_site", Some(0)),
            ("panda_hand", Some(5)),
            ("hand_camera", None),
            ("panda_link8", None),
            ("wrist_3_link", None),
            ("", None),
        ] {
            assert_eq!(tool_rank(name), rank, "{name}");
        }
        assert_eq!(pick_tool(&["ee_link", "tool0", "base"]), Ok(Some("tool0")));
        assert_eq!(
            pick_tool(&["panda_link8", "panda_hand", "panda_hand_tcp"]),
            Ok(Some("panda_hand_tcp"))
        );
        assert_eq!(pick_tool(&["a", "b"]), Ok(None));
        assert_eq!(pick_tool(&["left_tcp", "right_tcp", "flange"]), Err(vec!["left_tcp", "right_tcp"]));
        assert_eq!(gripper_word("panda_finger_joint1"), Some("finger"));
        assert_eq!(gripper_word("jointGripper"), Some("gripper"));
        assert_eq!(gripper_word("wrist_3_joint"), None);
    }
}
