//! The examples and exit codes `--help` prints after the options.

pub(crate) const AFTER_HELP: &str = "\
Examples:
  validate-design designs/paper-real-world.json                 # the paper's robot on scenarios/course.json
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-07.json --json ur5e-07.json
  validate-design designs/modular-elbow.json --scenario scenarios/workspace/pose.json --engines none
  validate-design designs/paper-real-world.json --engines mujoco --seed 3 --ik-seeds 8 --contact-depth 0.0005
  validate-design designs/ur10e.json --tolerance position --margin 0.01 --threads 1 --quiet
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-00.json --planner straight
  validate-design designs/ur20.json --scenario scenarios/cluttered/task-12.json --plan-budget 50000
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-03.json --reach-only
  validate-design modular6/Ll-Is-Ll-Il-D-Ls --scenario scenarios/cluttered/task-00.json --home 0,-1.2,1.1,-1.4,-1.5,0.2
  validate-design designs/economic-scara.json --scenario scenarios/cluttered/task-24.json --reach-only --search-boxes 1000000
  validate-design designs/urdf/example-robot-data/robots/panda_description/urdf/panda.urdf --srdf designs/urdf/example-robot-data/robots/panda_description/srdf/panda.srdf
  validate-design robot.urdf --base base_link --tip tool0 --package-path ~/ws/src --strict --kinematics-only
  validate-design robot.xml --kinematics-only --mujoco-checks 20
  validate-design designs/ur5e.json --describe --export-urdf ur5e.urdf --export-mjcf ur5e.xml
  validate-design designs/paper-real-world.json --svg pictures --png pictures --html report.html
  validate-design designs/ur5e.json --scenario scenarios/cluttered/task-07.json --export-mjcf scene.xml --scene --describe
  validate-design generate cluttered --all --out scenarios/cluttered --force
  validate-design generate workspace --tolerance z_symmetric --scale 1.2 --out /tmp/workspace.json
  validate-design designs/timor/improv-6r.json --scenario task.json   # a Timor assembly on a Timor / CoBRA task
  validate-design convert scenarios/cluttered/task-00.json --to timor --out task-00.timor.json
  validate-design workflow scenarios/cluttered/task-00.json --out workflow-00   # candidates to summary.html
  validate-design snapshot --suite proving-ground.json             # your own golden suite
  validate-design snapshot --suite proving-ground.json --accept    # record its new snapshots
  validate-design sweep catalog:modular6 --scenarios scenarios/cluttered/task-00.json --out bf-00   # brute force
  validate-design sweep catalog:modular6 --scenarios scenarios/cluttered/task-00.json --top 5 --best-designs best-00
  validate-design sweep 'designs/*.json' --scenarios scenarios/cluttered --full --engines none --out runs-1 --shard 1/2
  validate-design merge runs-1 runs-2 --out runs      # the shards joined: what the unsharded sweep writes
  validate-design sweep designs/ur5e.json --scenarios scenarios/cluttered/task-00.json --reference bf-00
  validate-design table1                              # the paper's Table 1 beside ours
  validate-design ga --scenario scenarios/cluttered/task-00.json --seed 1 --reference bf-00 --out ga-00.json
  validate-design ga --scenario scenarios/cluttered/task-00.json --best-design best-ga-00.json --force

Exit codes:
  0  the design passes the scenario (every goal reached by a certified collision-free path,
     held by every engine run, no contact, no joint over its rating under gravity); with
     --describe or --kinematics-only: the model was built (and MuJoCo agrees with our kinematics)
  1  the design fails, proven: the verdict line (FAIL) lists the reasons: a goal proven
     unreachable, a contact, a joint over its rating (or MuJoCo disagrees with our kinematics
     on the export by more than 1e-9 m / rad)
  2  bad input or usage: the message names the file and the field or line (also a limit
     passed, an output that is a file the run read, a failed write, MuJoCo missing)
  3  undecided: nothing failed, but the harness's limits left something open; the verdict
     line (UNDECIDED) names it: a goal neither reached nor proven unreachable (IK starts), a
     path not found within the planner's budget
  optimize: as validation, of the designs written (tuned, or kept where tuning lost ground): 1
     when one fails, else 3 when one is undecided, else 0; 2 bad input
  snapshot: 0 every snapshot matches (or was accepted), 1 a difference, new snapshot or
     orphan, 2 bad input
  sweep, merge, table1, ga: 0 the runs finished (whatever the designs' verdicts: they are in the
     results), 2 bad input, a folder that holds something else or is in use by another run, or
     a pair that could not run; 130 / 143 a sweep stopped by SIGINT / SIGTERM (every finished
     pair kept: run it again to resume)

Environment:
  ROS_PACKAGE_PATH  extra ':'-separated roots for package:// mesh URIs
  MUJOCO_LIBRARY    the MuJoCo library file to load instead of the one the build fetched";
