"""gente_quadruped: the 12-DoF, 14 kg quadruped (legged_gente/resources/robots/gente_quadruped), on the biped's terrains.

Only config subclasses: the quadruped needs no reward of its own. Reward scales follow legged_gym's
defaults for small quadrupeds (tracking, lin_vel_z, ang_vel_xy, torques, dof_acc, feet_air_time, collision,
action_rate, dof_pos_limits); water and river depths are scaled to the robot (trunk 0.3 m above the feet).
"""

from __future__ import annotations

from legged_gente.envs.base.legged_robot_config import LeggedRobotCfg, LeggedRobotCfgPPO


class GenteQuadrupedCfg(LeggedRobotCfg):
    class env(LeggedRobotCfg.env):
        num_envs = 4096
        episode_length_s = 20.0

    class terrain(LeggedRobotCfg.terrain):
        """The biped's curriculum (rows: difficulty, columns: type). The geometric terrains keep their
        difficulty ramps (steps, blocks and waves up to 0.2 m, rocks 0.25 m, like legged_gym's curriculum);
        the water is fixed shallow enough to wade: 0.15 m in the river and 0.12 m in the current's 0.2 m basin,
        about half the trunk height, where the biped gets up to 0.5 m. The per-type params after ':' replace the
        curriculum's value on every level."""

        mesh_type = "heightfield"
        mode = "curriculum"
        num_rows = 10
        num_cols = 20
        terrain_types = [
            "flat", "random_uniform", "natural_ground", "pyramid_slope", "pyramid_slope:direction=down",
            "pyramid_stairs", "pyramid_stairs:direction=down", "discrete_obstacles", "rocks", "waves",
            "river:depth=0.2+water:depth=0.15", "basin:depth=0.2+water:depth=0.12,flow=current,speed=0.3",
            "hills+soil:preset=dry_sand", "soil:preset=mud", "low_friction",
        ]
        terrain_proportions = [0.15, 0.1, 0.05, 0.075, 0.075, 0.05, 0.05, 0.05, 0.05, 0.05,
                               0.075, 0.05, 0.075, 0.05, 0.05]

    class init_state(LeggedRobotCfg.init_state):
        pos = [0.0, 0.0, 0.33]  # m; the stand keyframe has the trunk at 0.299 m, drop from 3 cm above it
        default_joint_angles = {  # the stand keyframe: feet right below the hips, knees behind
            "*_hip": 0.0,
            "*_thigh": 0.8,
            "*_calf": -1.6,
        }

    class control(LeggedRobotCfg.control):
        # The file's kp 40 / kv 1 just hold a PD stand without a policy (docs/robots.md); a policy balances
        # with softer, more compliant joints (legged_gym's 12 kg quadruped: kp 20, kd 0.5).
        stiffness = {"hip": 30.0, "thigh": 30.0, "calf": 30.0}  # N*m/rad, by joint-name substring
        damping = {"hip": 0.8, "thigh": 0.8, "calf": 0.8}  # N*m*s/rad
        action_scale = 0.25
        decimation = 4

    class asset(LeggedRobotCfg.asset):
        file = "resources/robots/gente_quadruped/gente_quadruped.xml"
        foot_bodies = ["*_foot"]
        penalize_contacts_on = ["*_thigh", "*_calf"]
        terminate_after_contacts_on = ["trunk"]
        terminate_height = 0.0
        terminate_tilt = 1.0

    class forces(LeggedRobotCfg.forces):
        # wading: the thigh (r 0.025 m) and calf (r 0.02 m) capsules; soil: the foot spheres, whose soles
        # TerrainForces derives from the geom (sole_length/width None): discs of radius 0.02 m
        leg_geom_names = [f"{leg}_{part}_geom" for leg in ("FL", "FR", "RL", "RR") for part in ("thigh", "calf")]
        foot_geom_names = [f"{leg}_foot_geom" for leg in ("FL", "FR", "RL", "RR")]
        # the calves' collision capsules are as wide as the foot balls: in soil they follow their foot into its rut
        rut_leg_geom_names = [f"{leg}_calf_collision" for leg in ("FL", "FR", "RL", "RR")]

    class rewards(LeggedRobotCfg.rewards):
        base_height_target = 0.3  # m, also the reference height of the height scan
        only_positive_rewards = True
        feet_air_time_target = 0.5  # s

        class scales(LeggedRobotCfg.rewards.scales):
            tracking_lin_vel = 1.0
            tracking_ang_vel = 0.5
            lin_vel_z = -2.0
            ang_vel_xy = -0.05
            orientation = -0.0
            torques = -0.0002
            dof_acc = -2.5e-7
            base_height = -0.0
            feet_air_time = 1.0
            collision = -1.0
            action_rate = -0.01
            dof_pos_limits = -10.0
            termination = -0.0


class GenteQuadrupedCfgPPO(LeggedRobotCfgPPO):
    class runner(LeggedRobotCfgPPO.runner):
        experiment_name = "gente_quadruped"
        max_iterations = 1500


class GenteQuadrupedFlatCfg(GenteQuadrupedCfg):
    """The quadruped on flat ground: the quickest way to check a gait."""

    class terrain(GenteQuadrupedCfg.terrain):
        mesh_type = "plane"
        measure_heights = False


class GenteQuadrupedFlatCfgPPO(GenteQuadrupedCfgPPO):
    class runner(GenteQuadrupedCfgPPO.runner):
        experiment_name = "gente_quadruped_flat"
        max_iterations = 500
