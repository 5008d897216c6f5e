"""gente_biped: the 10-DoF biped of GenTe's H1 setup, written here from primitive geoms."""

from __future__ import annotations

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg, LeggedRobotCfgPPO
from legged_gente.envs.base.terms import ObsTerm


class GenteBipedCfg(LeggedRobotCfg):
    class env(LeggedRobotCfg.env):
        num_envs = 4096
        episode_length_s = 20.0

    class terrain(LeggedRobotCfg.terrain):
        """A curriculum over the basic geometric and physical terrains (rows: difficulty, columns: type)."""

        mesh_type = "heightfield"
        mode = "curriculum"
        max_init_terrain_level = 0  # a biped learning from scratch starts on the easiest row and climbs
        num_rows = 10
        num_cols = 20
        terrain_types = [
            "flat", "random_uniform", "natural_ground", "pyramid_slope", "pyramid_slope:direction=down",
            "pyramid_stairs", "pyramid_stairs:direction=down", "discrete_obstacles", "rocks", "waves",
            "river+water", "basin+water:flow=current,speed=0.5", "hills+soil:preset=dry_sand", "soil:preset=mud", "low_friction",
        ]
        # the current flows in a basin that holds it: on flat ground its water stood as a wall at the column's edges
        terrain_proportions = [0.15, 0.1, 0.05, 0.075, 0.075, 0.05, 0.05, 0.05, 0.05, 0.05,
                               0.075, 0.05, 0.075, 0.05, 0.05]

    class init_state(LeggedRobotCfg.init_state):
        pos = [0.0, 0.0, 1.03]  # m; the default pose stands at 1.0 m: dropped from 3 cm, above the ground at any reset noise
        default_joint_angles = {
            "*_hip_yaw": 0.0,
            "*_hip_roll": 0.0,
            "*_hip_pitch": -0.25,
            "*_knee": 0.55,
            "*_ankle": -0.3,
        }

    class control(LeggedRobotCfg.control):
        stiffness = {"hip": 150.0, "knee": 200.0, "ankle": 80.0}  # N*m/rad, matched by joint-name substring
        damping = {"hip": 5.0, "knee": 5.0, "ankle": 3.0}  # N*m*s/rad
        action_scale = 0.25
        decimation = 4

    class asset(LeggedRobotCfg.asset):
        file = "resources/robots/gente_biped/gente_biped.xml"
        foot_bodies = ["*_foot"]
        sole_geoms = ["*_sole_*"]  # the collision spheres under each foot: swing height is measured at them
        penalize_contacts_on = ["*_thigh", "*_shank"]
        terminate_after_contacts_on = ["pelvis", "torso"]
        hip_joints = ["*_hip_yaw", "*_hip_roll"]
        terminate_height = 0.5
        terminate_tilt = 1.0

    class forces(LeggedRobotCfg.forces):
        leg_geom_names = ["left_thigh_geom", "left_shank_geom", "right_thigh_geom", "right_shank_geom"]
        # the four sole spheres of each foot (the box is visual; docs/robots.md says why)
        foot_geom_names = [f"{side}_sole_{corner}" for side in ("left", "right")
                           for corner in ("toe_l", "toe_r", "heel_l", "heel_r")]
        foot_water_geom_names = ["left_foot_geom", "right_foot_geom"]  # the foot's volume feels the water

    class commands(LeggedRobotCfg.commands):
        class ranges(LeggedRobotCfg.commands.ranges):
            lin_vel_x = [-1.0, 1.0]
            lin_vel_y = [-0.5, 0.5]
            ang_vel_yaw = [-1.0, 1.0]

    class observations(LeggedRobotCfg.observations):
        class policy(LeggedRobotCfg.observations.policy):
            gait_clock = ObsTerm(fn="gait_clock")  # sin, cos of the first foot's gait phase

    class rewards(LeggedRobotCfg.rewards):
        base_height_target = 0.98
        only_positive_rewards = True
        gait_period = 0.8  # s, the gait clock's period
        stance_fraction = 0.55  # fraction of the period a foot should be on the ground
        swing_height_target = 0.08  # m, clearance of the sole (its lowest point) above the ground in swing

        class scales(LeggedRobotCfg.rewards.scales):
            tracking_lin_vel = 1.0
            tracking_ang_vel = 0.5
            lin_vel_z = -2.0
            ang_vel_xy = -0.05
            orientation = -1.0
            base_height = -10.0
            torques = -1.0e-5
            dof_acc = -2.5e-7
            action_rate = -0.01
            feet_air_time = 0.0
            collision = -1.0
            dof_pos_limits = -5.0
            alive = 0.15
            gait_contact = 0.18
            feet_swing_height = -20.0
            hip_deviation = -1.0
            no_fly = 0.0
            feet_slip = -0.2
            termination = -0.0


class GenteBipedCfgPPO(LeggedRobotCfgPPO):
    class runner(LeggedRobotCfgPPO.runner):
        experiment_name = "gente_biped"
        max_iterations = 1500


class GenteBipedFlatCfg(GenteBipedCfg):
    """The biped on flat ground: the quickest way to check a gait."""

    class terrain(GenteBipedCfg.terrain):
        mesh_type = "plane"
        measure_heights = False


class GenteBipedFlatCfgPPO(GenteBipedCfgPPO):
    class runner(GenteBipedCfgPPO.runner):
        experiment_name = "gente_biped_flat"
