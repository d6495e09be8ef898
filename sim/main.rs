fn main() { println!("{}", proving_ground::mujoco_probe()); }
