"""Configuration of a legged-robot locomotion task and of its PPO training (rsl-rl-lib 5.5).

Every robot-specific fact is given by *name* (bodies, joints, geoms): the environment resolves names
against the MJCF, so no body or DoF index is ever hard-coded.
"""

from __future__ import annotations

import math

from legged_gente.envs.base.base_config import BaseConfig, class_to_dict
from legged_gente.envs.base.terms import ObsTerm
from legged_gente.external_forces.config import ForcesConfig


class LeggedRobotCfg(BaseConfig):
    class env:
        num_envs = 4096
        env_spacing = 3.0  # m, grid spacing of robots on a plane
        episode_length_s = 20.0  # s
        send_timeouts = True  # report time-outs (extras["time_outs"]) so that PPO bootstraps their value

    class terrain:
        mesh_type = "plane"  # "plane" | "heightfield"
        mode = "curriculum"  # "curriculum" | "random" | "selected" | "generated"
        resolution = 0.1  # m, horizontal size of a heightfield cell
        # m, largest side of one MuJoCo heightfield geom: a larger terrain is laid down in pieces, as MuJoCo-Warp's
        # heightfield collision goes wrong far from a heightfield's centre (sim/assembly.py); rounded to whole cells
        hfield_piece_size = 20.0
        border_size = 5.0  # m, flat border around the tile grid
        terrain_length = 8.0  # m, tile size along x
        terrain_width = 8.0  # m, tile size along y
        num_rows = 10  # difficulty levels
        num_cols = 20  # terrain types
        terrain_types = ["flat", "random_uniform"]
        terrain_proportions = [0.5, 0.5]
        selected_terrain: str | None = None  # atomic terrain name for mode "selected"
        selected_params: dict = {}
        generated_specs: list = []  # spec JSON paths for mode "generated"
        # difficulty of the last row (the first is 0): 1 is each terrain's standard top level (steps and obstacles
        # 0.2 m, slopes 0.4); more extends every terrain's ramp past it, up to 2 (registry.MAX_DIFFICULTY), for a
        # policy that has outgrown the standard curriculum
        max_difficulty = 1.0
        max_init_terrain_level = 5
        curriculum = True
        # a robot that solves the hardest level: "random" sends it to a random level (legged_gym; keeps the easy
        # levels in the training mix, and a policy that solves every tile then averages level 6.0 of 10), "stay"
        # keeps it on the hardest level (the mean level then climbs towards the top as the policy improves)
        solved_top_level = "random"
        static_friction = 1.0  # the ground's sliding friction; the robot's geoms get it too (a pair takes the larger)
        seed = 0
        # height scan (m, in the base's yaw frame): the "height_scan" observation on a heightfield
        measure_heights = True
        measured_points_x = [-0.8 + 0.1 * i for i in range(17)]
        measured_points_y = [-0.5 + 0.1 * i for i in range(11)]

    class commands:
        resampling_time = 10.0  # s
        heading_command = True  # yaw rate follows a heading error (except for stand-still commands)
        heading_stiffness = 0.5  # 1/s, yaw rate per rad of heading error
        still_fraction = 0.1  # fraction of resampled commands that ask the robot to stand still
        # commands.ranges, heading_stiffness and still_fraction are read by the step from device tensors
        # (env.params.commands); change them at run time with env.set_param("commands.ranges.lin_vel_x", [a, b])

        class ranges:
            lin_vel_x = [-1.0, 1.0]  # m/s
            lin_vel_y = [-0.5, 0.5]  # m/s
            ang_vel_yaw = [-1.0, 1.0]  # rad/s
            heading = [-math.pi, math.pi]  # rad

    class init_state:
        """The state every reset starts from; domain_rand.random_init_yaw / init_lin_vel_xy_noise add to it."""

        pos = [0.0, 0.0, 1.0]  # m, base position above the spawn point
        rot = [1.0, 0.0, 0.0, 0.0]  # (w, x, y, z), base orientation
        lin_vel = [0.0, 0.0, 0.0]  # m/s, base linear velocity in the world frame
        ang_vel = [0.0, 0.0, 0.0]  # rad/s, base angular velocity in the base frame (MuJoCo's free joint)
        default_joint_angles: dict = {}  # joint name or fnmatch pattern -> rad
        joint_pos_noise = 0.1  # rad, uniform noise on reset

    class control:
        stiffness: dict = {}  # joint-name pattern -> N*m/rad
        damping: dict = {}  # joint-name pattern -> N*m*s/rad
        action_scale = 0.25  # rad per unit action
        decimation = 4  # physics substeps per policy step

    class asset:
        file = ""  # MJCF path; a relative one is looked up in the working directory, then in the legged_gente package
        base_body = ""  # the floating base (body with the free joint); "" = the free joint's body
        foot_bodies: list = []  # names or fnmatch patterns
        penalize_contacts_on: list = []  # bodies whose contacts are penalised (and therefore collide)
        terminate_after_contacts_on: list = []  # bodies whose contacts end the episode
        hip_joints: list = []  # joints penalised for deviating from default (biped hip yaw/roll)
        terminate_height = 0.0  # m above the ground under the base; 0 disables
        terminate_tilt = 1.0  # rad of base tilt that ends the episode, in (0, pi]; pi: never

    class domain_rand:
        random_init_yaw = True  # each reset turns init_state.rot by a yaw drawn uniformly in [-pi, pi)
        init_lin_vel_xy_noise = 0.5  # m/s, each reset adds U(-a, a) to init_state.lin_vel's x and y; 0: none
        randomize_friction = True
        friction_range = [0.5, 1.25]
        randomize_base_mass = False
        added_mass_range = [-1.0, 3.0]  # kg
        push_robots = True
        push_interval_s = 15.0
        # a push is an impulse: it adds U(-max, max) m/s to the base's x and y velocity (legged_gym sets the
        # velocity to that draw instead, so a walking robot's push there can also slow it)
        max_push_vel_xy = 1.0  # m/s

    class rewards:
        class scales:
            termination = -0.0
            tracking_lin_vel = 1.0
            tracking_ang_vel = 0.5
            lin_vel_z = -2.0
            ang_vel_xy = -0.05
            orientation = -0.0
            torques = -0.00001
            dof_vel = -0.0
            dof_acc = -2.5e-7
            base_height = -0.0
            feet_air_time = 1.0
            collision = -1.0
            feet_stumble = -0.0
            action_rate = -0.01
            stand_still = -0.0
            dof_pos_limits = -0.0
            feet_contact_forces = -0.0

        only_positive_rewards = True  # clip the step's total reward at zero (helps early learning)
        tracking_sigma = 0.25  # (m/s)^2, width of the exp(-err^2/sigma) tracking kernel
        soft_dof_pos_limit = 0.9  # fraction of the joint range before dof_pos_limits starts penalising
        base_height_target = 1.0  # m
        max_contact_force = 500.0  # N, above this feet_contact_forces penalises
        feet_air_time_target = 0.5  # s
        soft_torque_limit = 1.0  # fraction of the actuator's force limit above which torque_limits penalises
        # every number in this class (scales included) is read by the step from device tensors (env.params.rewards,
        # env.reward_scale_vec): change them at run time with env.set_param("rewards.tracking_sigma", 0.2) or
        # env.set_param("rewards.scales.feet_air_time", 2.0)

    class observations:
        """One table per group: each term's function, scale, noise and clip (see terms.ObsTerm). The critic sees
        the policy's terms without noise, then its own (privileged) terms."""

        class policy:
            base_lin_vel = ObsTerm(fn="base_lin_vel", scale=2.0, noise=0.1)
            base_ang_vel = ObsTerm(fn="base_ang_vel", scale=0.25, noise=0.2)
            projected_gravity = ObsTerm(fn="projected_gravity", noise=0.05)
            commands = ObsTerm(fn="commands", scale=(2.0, 2.0, 0.25))  # vx, vy, yaw rate
            dof_pos = ObsTerm(fn="dof_pos", scale=1.0, noise=0.01)  # relative to the default pose
            dof_vel = ObsTerm(fn="dof_vel", scale=0.05, noise=1.5)
            actions = ObsTerm(fn="actions")
            height_scan = ObsTerm(fn="height_scan", scale=5.0, noise=0.1, clip=(-1.0, 1.0), when="heightfield")

        class critic:
            friction = ObsTerm(fn="friction")
            added_base_mass = ObsTerm(fn="added_base_mass")  # kg
            feet_contact_forces = ObsTerm(fn="feet_contact_forces", scale=0.01)  # N
            force_fields = ObsTerm(fn="force_fields", when="forces")

    class normalization:
        clip_observations = 100.0
        clip_actions = 100.0

    class noise:
        add_noise = True  # the policy's observations get each term's noise (cfg.observations)
        noise_level = 1.0  # multiplies every term's noise

    class sim:
        dt = 0.005  # s, physics substep
        gravity = [0.0, 0.0, -9.81]
        integrator = "implicitfast"  # "euler" | "implicitfast"
        solver = "newton"  # "newton" | "cg"
        iterations = 10  # Newton usually converges in 2-4; the cap bounds the slowest world
        ls_iterations = 20
        cone = "pyramidal"
        nconmax = 32  # contacts per world (contact arrays are shared: naconmax = nconmax * num_envs)
        njmax = 160  # constraint rows per world: 4 per pyramidal condim-3 contact + joint limits; a fallen robot
        # on rough ground can touch with many bodies at once, and an overflowing world is reset as diverged
        # on GPU: "env_step" records the whole step (physics, force kernels, rewards, resets, observations)
        # into one CUDA graph (envs/base/step_runner.py); "physics" only the substep loop (for env code that
        # branches on host values); "off" launches everything one by one. Ignored on the CPU.
        cuda_graph = "env_step"
        # on GPU: torch.compile the step's torch logic (rewards, terminations, resets, curriculum, observations),
        # which fuses its few hundred small operations into a few dozen kernels; compiled at the second step (the
        # first runs eagerly: StepRunner checks that it reads no cfg)
        torch_compile = True
        # m/s or rad/s; a world moving faster has diverged (real ones reach 1e6+): it is reset (as a time-out, not
        # counted in the curriculum or the episode statistics) and counted in Episode/diverged_resets
        max_qvel = 1000.0

    class forces(ForcesConfig):
        """Terrain force fields (water, soil, ground friction) where the material map has them. Leg and foot geoms
        are named by the robot's config."""

        enabled = True  # off: no force kernels are installed at all
        # the fields scale contact friction by cell friction / the ground geom's friction, which in an env is
        # terrain.static_friction: one setting, so this one stays None (the env passes static_friction)
        friction_reference: float | None = None


class LeggedRobotCfgPPO(BaseConfig):
    seed = 1

    class actor:
        class_name = "MLPModel"
        hidden_dims = [512, 256, 128]
        activation = "elu"
        obs_normalization = True

        class distribution_cfg:
            class_name = "legged_gente.utils.ppo:SyncFreeGaussianDistribution"  # rsl-rl's, sampled without a sync
            init_std = 1.0
            std_type = "scalar"

    class critic:
        class_name = "MLPModel"
        hidden_dims = [512, 256, 128]
        activation = "elu"
        obs_normalization = True

    class algorithm:
        # rsl-rl's PPO with a sync-free update (same math; "PPO" selects rsl-rl's own)
        class_name = "legged_gente.utils.ppo:GentePPO"
        value_loss_coef = 1.0
        use_clipped_value_loss = True
        clip_param = 0.2
        entropy_coef = 0.01
        num_learning_epochs = 5
        num_mini_batches = 4
        learning_rate = 1.0e-3
        schedule = "adaptive"
        gamma = 0.99
        lam = 0.95
        desired_kl = 0.01
        max_grad_norm = 1.0
        # bf16 autocast in the loss's forward pass (rsl-rl's option), on CUDA devices only (on the CPU it made the
        # update slower, so the runner keeps fp32 there). On an H100 at 8192 robots with the compiled update: PPO
        # +7 % (the update 16-17 % of an iteration instead of 22 %); two seeds of 1000 iterations learned per
        # iteration as fp32 did (docs/performance_log.md)
        use_mixed_precision = True

    class runner:
        num_steps_per_env = 24
        max_iterations = 1500
        save_interval = 50
        experiment_name = "legged_robot"
        run_name = ""
        logger = "tensorboard"
        check_for_nan = False  # the env resets non-finite worlds itself; the check costs a sync per step
        # float32 matrix products (torch.set_float32_matmul_precision): "high" lets the PPO update use TF32
        # tensor cores on Ampere and newer GPUs (several times faster GEMMs, 10-bit mantissa inputs with fp32
        # accumulation); "highest" keeps full fp32. Applied on CUDA devices only.
        matmul_precision = "high"
        # CUDA: GentePPO's update runs the actor's and critic's MLPs compiled by TorchInductor
        # (GentePPO.compile_update); on an H100 at 8192 robots the update took 63-64 ms instead of 69-70 ms
        # (PPO +2.0 %; docs/performance_log.md)
        compile_update = True
        obs_groups = {"actor": ["policy"], "critic": ["critic"]}
        # fine-tuning a shipped policy (gente-train --pretrained): its critic is not shipped, so the first
        # iterations train the fresh critic alone, the actor held fixed (GentePPO.freeze_actor). Meanwhile the
        # shipped actor carries the restarted curriculum up (to level ~10 of the biped's 0-15 by iteration 800):
        # an actor released on the bottom levels specialises to them and lost 3x more on gente_original
        # (docs/performance_log.md; chosen on that evaluation set, which biases its score there). Ignored when
        # training from scratch or resuming.
        critic_warmup_iterations = 800
        resume = False
        load_run = -1  # -1: the latest run
        checkpoint = -1  # -1: the latest checkpoint


def rsl_rl_train_cfg(cfg: LeggedRobotCfgPPO) -> dict:
    """The train-cfg dict rsl-rl-lib 5.5's OnPolicyRunner expects, built from a config instance."""
    runner = class_to_dict(cfg.runner)
    return {
        "seed": cfg.seed,
        "num_steps_per_env": runner["num_steps_per_env"],
        "save_interval": runner["save_interval"],
        "experiment_name": runner["experiment_name"],
        "run_name": runner["run_name"],
        "logger": runner["logger"],
        "check_for_nan": runner["check_for_nan"],
        "matmul_precision": runner["matmul_precision"],
        "compile_update": runner["compile_update"],
        "obs_groups": runner["obs_groups"],
        "actor": class_to_dict(cfg.actor),
        "critic": class_to_dict(cfg.critic),
        "algorithm": class_to_dict(cfg.algorithm),
    }
