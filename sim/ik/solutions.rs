//! What an all-solutions method returns for one pose.

/// Every solution of one pose, unpolished, each with six angles (the sixth is the virtual
/// joint's for a 5R arm).
#[derive(Debug, Clone, Default)]
pub struct Solutions {
    /// The configurations, angles in (-pi, pi].
    pub configurations: Vec<[f64; 6]>,
    /// Every solution is listed, given each is verified (see the methods' `resolved`).
    pub resolved: bool,
    /// Why no configuration reaches the pose within the tolerance, when a method proves it.
    pub out_of_reach: Option<String>,
}
