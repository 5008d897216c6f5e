"""The attributes the terrain force fields read; light to import (no simulator), so config classes can use it."""

from __future__ import annotations


class ForcesConfig:
    """Attributes TerrainForces reads (subclass or copy these onto your env config's ``forces`` class).

    wading: bool          drag, buoyancy, added mass (and paper flow force) on leg segments and feet in water
    soil: bool            Bekker sinkage, bulldozing and Mohr-Coulomb / Janosi-Hanamoto traction limit for feet on
                          soil cells
    friction_from_map: bool  ground contacts' tangential friction scaled by the cell's MaterialMap.friction
    friction_reference: float  friction of the MJCF ground geom (1): a cell of this friction changes nothing
    water_density: float  rho, kg/m^3
    drag_coefficient: float  cd of a cylinder across the flow (1), ~1.0-1.2 at leg Reynolds numbers (Hoerner)
    added_mass_coefficient: float  ca (1), 1.0 for a circular cylinder; a fixed leg in accelerating flow feels
                           Morison's inertia with cm = 1 + ca (Froude-Krylov + added mass)
    plate_drag_coefficient: float  cd of a box sole's faces as flat plates normal to the flow (1.17, Hoerner)
    sphere_drag_coefficient: float  cd of a sphere sole (0.47, Hoerner, subcritical)
    noise_std: float      std of the paper's eps (per episode, drag and vertical forces) and xi (per step, flow)
    vertical_drag: bool   the legs' cross-flow drag on the full relative velocity (True); False drops its
                           vertical part first (the paper's horizontal-only drag, of its leg model: the feet,
                           which the paper does not model, keep their drag on the full relative velocity)
    paper_drag_area: bool  GenTe's A = 2 pi r h instead of the projected 2 r h
    paper_added_mass: bool GenTe's effective weight (added mass only adds weight) instead of the added mass as
                           inertia in the mass matrix (docs/forces.md)
    paper_flow_force: bool add GenTe's flow term as a force (N) on each submerged segment, on top of the
                           flow entering the drag as a velocity
    leg_geom_names: list[str]   capsule (or cylinder) geoms of the legs that feel water
    foot_geom_names: list[str]  colliding geoms of the feet that sink into soil; geoms on one body form one
                           foot (a box sole, or e.g. the spheres at its corners)
    rut_leg_geom_names: list[str]  capsule geoms of the legs, each above one foot and no wider than its sole (the
                           quadruped's calves, as wide as their foot balls), that follow their foot down the hole it
                           presses into soil and press ruts of their own under their own load: with the analytic sole
                           contacts (``sole_contact``) they touch the terrain through the same kernel, over soil
                           against the surface lowered by the deeper of their own rut and their foot's, instead of
                           MuJoCo's collision (the model must not collide them: ``contact.exclude_sole_collisions``)
    foot_water_geom_names: list[str] | None  sphere or box geoms of the feet that feel water (buoyancy, drag);
                           None: the foot_geom_names
    sole_length, sole_width: float | None  a rectangular sole's size (m) along the foot body's x and y axes (both or
                           neither); None:
                           the footprint of the first foot's geoms in its body's x-y plane, each as it is turned in
                           the body (a lone sphere, or a lone upright capsule or cylinder: a disc of its radius; else
                           the rectangle around the geoms)
    contact_threshold: float  foot normal force (N) above which the force fields count a foot as in contact (its slip
                          since touchdown, its lift-off); the env's ``foot_contacts()``, which the gait rewards read,
                          is legged_gym's vertical contact force above 1 N, not this
    liftoff_time: float   a foot whose normal force stays at or below contact_threshold this long (s) has ended
                          its stance, and lifted off, its slip and rut forgotten, if it is also clear of the ground
                          (liftoff_clearance); shorter dips are solver chatter, not lift-off (a gait's swing is ten
                          times longer)
    liftoff_clearance: float  height (m) of an analytic sole contact's sphere above the floor it stood on (its rut's)
                          below which its foot's stance goes on, and above the unlowered ground below which it has
                          not lifted off, whatever its normal force: MuJoCo's contact sliding on a firm soil hops
                          off for 20-150 ms at a time, up to 2.3 cm high at 2-4 m/s, and a lift-off forgets the slip
                          (Janosi-Hanamoto's traction restarts from 0). MuJoCo-collided feet (sole_contact off, box
                          soles) have only liftoff_time
    min_friction: float   a ground contact whose friction is below this is made frictionless (condim 1): as mu -> 0
                          MuJoCo's pyramidal cone holds a tangential load by inflating the normal force (the foot
                          is launched) and its elliptic cone divides by mu
    soil_friction_cap: float  most friction coefficient a soil contact gets: its traction (c A + F_N tan phi)
                          over F_N grows without bound as F_N -> 0 through the cohesion term
    sole_contact: bool    sphere and capsule foot geoms touch the terrain through analytic contacts
                          (``contact.py``: the triangulated heightfield, the rut shown in full) instead of
                          MuJoCo's heightfield collision; the model must not collide them with the terrain
                          (``contact.exclude_sole_collisions``)
    sole_contact_max_depth: float  deepest penetration (m) an analytic sole contact gives the solver. Walking
                          loads press a sole a few mm in (its rut is shown by lowering the surface, not by
                          penetration); deeper, the sphere has been pushed through a wall or into a pillar
                          (only the feet touch the terrain), and MuJoCo's soft contact would push it out at up
                          to depth / (2 dmax timeconst): 26 m/s from 1 m inside a pillar. Capped, at most
                          0.03 / (2 * 0.95 * 0.02 s) = 0.8 m/s
    terrain_contact_max_depth: float  deepest penetration (m) any other terrain contact (MuJoCo's heightfield
                          collision: legs, body, box soles) gives the solver. A limb that enters a tall column (a
                          tree, a pillar: a few cells of the heightfield) from its side is collided with the
                          column's top prism face, metres above it (a biped shank 2.45 m "deep" in a 3 m tree was
                          seen leaving at 11-28 m/s); the column's side contacts, a few cm deep, push it out.
                          Capped as the soles, at most 0.03 / (2 * 0.95 * 0.02 s) = 0.8 m/s. With soil it must
                          exceed max_rut_depth (the rut is shown after the cap: a foot in it would get no
                          contact). Applied by the force fields' contact filter: an env without force fields
                          (forces off, or no water, soil, map friction or analytic soles) has no cap
    bulldozing_speed_reg: float  speed (m/s) below which the RFT soils' horizontal force, and the bulldozing
                          reported to the viewer, fade out linearly (Bekker's bulldozing acts through the
                          contacts' friction limit)
    sinkage_rate: float   fastest the rut under a foot deepens (m/s); keeps the force->sinkage loop stable
    sinkage_load_tau: float  time constant (s) of each of the two first-order low-passes in series on F_N that
                          drive the sinkage (the first alone is the fast load of the friction limit, below): a
                          foot's soft contact chatters while its rut deepens, and the rut keeps every peak
    traction_load_tau: float  the load the soil's cohesion share of a foot's contact friction, c A / F, divides by
                          is the larger of F_N low-passed over sinkage_load_tau and F_N's mean since touchdown,
                          after this long (s) low-passed with this time constant: long against a sliding contact's
                          hops (its friction force then averages to Mohr-Coulomb's c A + W tan(phi)), short against
                          a stance; an unloading foot holds less than Mohr-Coulomb for about this long
    max_rut_depth: float  deepest a MuJoCo-collided foot (box soles, or sole_contact off) is shown lowered into its
                           rut (m); the forces use the full sinkage. MuJoCo's heightfield contacts go wrong once a
                           geom is ~3 cm inside a cell (docs/forces.md); analytic sole contacts show the full rut
    parallel_kernels: bool  on a GPU, the legs' water, the feet's water and the soil (independent kernels) run as
                          concurrent branches, each on a stream of its own, and so do the feet's cells and the
                          contact filter where no foot is in MuJoCo's contacts; False: one after another (the forces
                          are the same, up to the order in which the atomic adds sum them)
    """

    wading = True
    soil = True
    friction_from_map = True
    friction_reference = 1.0
    water_density = 1000.0
    drag_coefficient = 1.1
    added_mass_coefficient = 1.0
    noise_std = 0.1
    plate_drag_coefficient = 1.17
    sphere_drag_coefficient = 0.47
    vertical_drag = True
    paper_drag_area = False
    paper_added_mass = False
    paper_flow_force = False
    leg_geom_names: list[str] = []
    foot_geom_names: list[str] = []
    rut_leg_geom_names: list[str] = []
    foot_water_geom_names: list[str] | None = None
    sole_length: float | None = None
    sole_width: float | None = None
    contact_threshold = 1.0
    liftoff_time = 0.05
    liftoff_clearance = 0.025
    soil_friction_cap = 2.0
    min_friction = 0.01
    sole_contact = True
    sole_contact_max_depth = 0.03
    terrain_contact_max_depth = 0.03
    bulldozing_speed_reg = 0.05
    sinkage_rate = 0.5
    max_rut_depth = 0.01
    sinkage_load_tau = 0.05
    traction_load_tau = 0.3
    parallel_kernels = True
