//! proving-ground
pub fn mujoco_probe() -> usize {
    let m = mujoco_rs::wrappers::mj_model::MjModel::from_xml_string("<mujoco><worldbody><body><joint type='hinge'/><geom size='0.1'/></body></worldbody></mujoco>").unwrap();
    m.ffi().nbody as usize
}
