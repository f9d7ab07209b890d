"""Scene schema: the validated, frozen config objects a scene YAML file becomes (pydantic models).

All values are SI. A key whose unit is not obvious carries it as a suffix (``_m``, ``_s``, ``_kg``,
``_n``, ``_deg``, ``_kg_m`` for kg per metre, ``_pa_m`` for Pa per metre). Dimensionless coefficients have
no suffix. Validation is done by pydantic (chosen over hand-written checks because it gives strict
unknown-key rejection, type coercion rules and range constraints with a machine-readable error location).
Reading a scene file, the library entries, ``--set`` overrides and the one-line error messages are in
:mod:`moor_env.config`.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator


class _Strict(BaseModel):
    """Base: unknown keys are errors, objects are immutable, no silent float->int coercion."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=False)


class CurrentConfig(_Strict):
    """Steady current: piecewise-linear speed over depth, one horizontal direction.

    Below the deepest profile point the speed falls linearly to 0 at the seabed.
    """

    profile: tuple[tuple[float, float], ...] = Field(
        default=((0.0, 0.8), (300.0, 0.6), (400.0, 0.2)),
        description="(depth below surface [m], speed [m/s]) pairs, depths increasing",
    )
    direction_deg: float = Field(0.0, ge=-360.0, le=360.0,
                                 description="direction the current flows towards, from +x towards +y [deg]")
    scale: float = Field(1.0, ge=0.0, le=5.0, description="multiplies every profile speed; 0 switches current off")

    @model_validator(mode="after")
    def _check_profile(self) -> CurrentConfig:
        depths = [p[0] for p in self.profile]
        if any(d < 0 for d in depths) or any(b <= a for a, b in zip(depths, depths[1:], strict=False)):
            raise ValueError("profile depths must be >= 0 and strictly increasing")
        if any(abs(p[1]) > 5.0 for p in self.profile):
            raise ValueError("profile speeds must be within -5 .. 5 m/s")
        return self


class SeabedConfig(_Strict):
    """Flat seabed at ``-water_depth_m``: vertical spring-damper contact and Coulomb friction for line nodes."""

    stiffness_pa_m: float = Field(3.0e6, gt=0.0, le=1.0e9,
                                  description="contact pressure per metre of penetration [Pa/m]")
    damping_pa_s_m: float = Field(3.0e5, ge=0.0, le=1.0e8,
                                  description="contact pressure per m/s of penetration rate [Pa s/m]")
    friction_coefficient: float = Field(0.5, ge=0.0, le=2.0)
    friction_velocity_m_s: float = Field(0.05, gt=0.0, le=1.0,
                                         description="sliding speed below which friction is ramped linearly [m/s]")


class SeaStateConfig(_Strict):
    """Irregular sea (JONSWAP) driving the vessel tops through a simple motion transfer (see physics.vessels)."""

    hs_m: float = Field(0.0, ge=0.0, le=16.0, description="significant wave height [m]; 0 is calm")
    tp_s: float = Field(10.0, ge=3.0, le=25.0, description="spectral peak period [s]")
    gamma: float = Field(3.3, ge=1.0, le=10.0, description="JONSWAP peak enhancement")
    n_components: int = Field(64, ge=8, le=1024)
    seed: int = Field(0, ge=0, description="seed of the random component phases")
    vessel_natural_period_s: float = Field(9.0, ge=2.0, le=40.0,
                                           description="heave/surge natural period of the vessels [s]")
    vessel_damping_ratio: float = Field(0.3, gt=0.0, le=2.0)


class EnvironmentConfig(_Strict):
    """Water, seabed, current and sea state."""

    water_depth_m: float = Field(..., gt=10.0, le=6000.0)
    gravity_m_s2: float = Field(9.81, gt=0.0, le=20.0)
    water_density_kg_m3: float = Field(1025.0, ge=900.0, le=1100.0)
    current: CurrentConfig = CurrentConfig(scale=0.0)
    seabed: SeabedConfig = SeabedConfig()
    sea_state: SeaStateConfig = SeaStateConfig()


class MaterialConfig(_Strict):
    """A line material (chain, wire, fibre rope).

    Reference areas: normal drag on ``diameter_m`` per metre; tangential drag on the wetted perimeter
    ``pi * diameter_m`` per metre (RIFLEX and MoorDyn convention; the seed's chain value 0.0069 uses it);
    added mass on ``pi/4 * diameter_m**2`` per metre.
    """

    diameter_m: float = Field(..., gt=0.0, le=2.0,
                              description="hydrodynamic diameter (drag and added-mass reference) [m]")
    mass_per_length_kg_m: float = Field(..., gt=0.0, le=5000.0, description="mass in air per unstretched metre [kg/m]")
    submerged_mass_per_length_kg_m: float | None = Field(
        None, description="mass in air minus displaced water per metre [kg/m]; default: from diameter_m"
    )
    ea_n: float = Field(..., gt=0.0, le=1.0e12, description="axial stiffness [N]")
    axial_damping_ratio: float = Field(
        0.3, ge=0.0, le=2.0, description="internal axial damping as a ratio of critical for one segment's axial mode")
    cd_normal: float = Field(..., ge=0.0, le=20.0)
    cd_tangential: float = Field(..., ge=0.0, le=5.0, description="tangential drag, wetted-perimeter (pi*D) reference")
    ca_normal: float = Field(1.0, ge=0.0, le=5.0)
    ca_tangential: float = Field(0.0, ge=0.0, le=5.0)
    mbl_n: float = Field(..., gt=0.0, le=1.0e9, description="minimum breaking load [N]")

    @model_validator(mode="after")
    def _check_submerged(self) -> MaterialConfig:
        if self.submerged_mass_per_length_kg_m is not None and not (
            -self.mass_per_length_kg_m < self.submerged_mass_per_length_kg_m <= self.mass_per_length_kg_m
        ):
            raise ValueError("submerged_mass_per_length_kg_m must lie in (-mass_per_length_kg_m, mass_per_length_kg_m]")
        return self


class AnchorSectionConfig(_Strict):
    """One axial section of the anchor, listed from the tip backwards."""

    length_m: float = Field(..., gt=0.0, le=50.0)
    outer_diameter_m: float = Field(..., gt=0.0, le=10.0,
                                    description="outer diameter: buoyancy, drag and added-mass reference [m]")
    flooded_diameter_m: float = Field(0.0, ge=0.0, le=10.0, description="diameter of the open, water-filled bore [m]")
    mass_per_length_kg_m: float = Field(..., gt=0.0, le=1.0e5, description="structural mass per metre [kg/m]")
    cd_normal: float = Field(..., ge=0.0, le=50.0, description="normal drag on outer_diameter_m (fins: much larger)")
    ca_normal: float = Field(1.0, ge=0.0, le=10.0)
    cd_tangential: float = Field(0.0, ge=0.0, le=10.0,
                                 description="skin friction on the wetted perimeter pi*outer_diameter_m")

    @model_validator(mode="after")
    def _check_bore(self) -> AnchorSectionConfig:
        if self.flooded_diameter_m >= self.outer_diameter_m:
            raise ValueError("flooded_diameter_m must be smaller than outer_diameter_m")
        return self


class AnchorConfig(_Strict):
    """Rigid dart anchor: sections from tip to back tip, end pressure drag on the end faces."""

    sections: tuple[AnchorSectionConfig, ...] = Field(..., min_length=1)
    tip_drag_coefficient: float = Field(0.387, ge=0.0, le=5.0,
                                        description="pressure drag on the tip face, reference pi/4*D^2")
    back_drag_coefficient: float = Field(0.043, ge=0.0, le=5.0,
                                         description="pressure drag on the back face, reference pi/4*D^2")
    mass_scale: float = Field(1.0, ge=0.5, le=1.5,
                              description="multiplies the structural mass (fabrication tolerance studies)")
    quadrature_points: int = Field(26, ge=4, le=400,
                                   description="points along the body for distributed drag and added mass")

    @property
    def length_m(self) -> float:
        """Total length of the anchor [m]."""
        return sum(s.length_m for s in self.sections)


class ReleaseUnitConfig(_Strict):
    """Release unit at the wire's lower end (stays on the wire after release)."""

    mass_kg: float = Field(1780.0, ge=0.0, le=1.0e5)
    volume_m3: float = Field(0.672, ge=0.0, le=100.0)
    drag_area_m2: float = Field(0.98, ge=0.0, le=100.0,
                                description="Cd times projected area, applied isotropically [m^2]")
    added_mass_coefficient: float = Field(1.0, ge=0.0, le=5.0, description="added mass as a multiple of rho*volume_m3")
    max_release_load_n: float = Field(273.0e3 * 9.81, gt=0.0, description="rated release load [N] (273 t)")


class ComponentsConfig(_Strict):
    """Which parts of the installation the scene simulates."""

    wire: bool = True
    vertical_chain: bool = True
    mooring_line: bool = True
    keep_wire_after_release: bool = False


class InstallationConfig(_Strict):
    """Geometry of a two-vessel dart-anchor installation, all in the x-z plane (seed 003: Landhaug 2015,
    *Dynamic Simulation of Dart Anchor Installation*, Models 1 and 2).

    The installation vessel (wire top) is at x = 0, the second vessel (mooring-line top) at
    x = ``vessel_spacing_m``. The bottom chain (``bottom_chain_length_m``) starts at the anchor's back tip:
    its first ``vertical_chain_length_m`` hang vertically to the release point, the rest forms the loop, then
    fibre up to the second vessel; ``mooring_line_length_m`` counts all of it. The wire length is solved so
    that the anchor tip hangs ``drop_height_m`` above the seabed at equilibrium.
    """

    vessel_spacing_m: float = Field(50.0, ge=0.0, le=3000.0)
    drop_height_m: float = Field(68.5, gt=1.0, le=500.0, description="anchor tip above the seabed at release [m]")
    vertical_chain_length_m: float = Field(50.0, ge=2.0, le=500.0)
    bottom_chain_length_m: float = Field(150.0, ge=2.0, le=2000.0)
    mooring_line_length_m: float = Field(540.0, gt=0.0, le=10000.0)
    wire_material: str = "wire_76"
    chain_material: str = "chain_142"
    fibre_material: str = "polyester_254"
    fairlead_depth_m: float = Field(0.0, ge=0.0, le=50.0, description="depth of both vessel hang-off points [m]")
    components: ComponentsConfig = ComponentsConfig()
    release_time_s: float = Field(0.0, ge=0.0, le=3600.0,
                                  description="pre-release simulated time before the release [s]")
    spacing_rate_m_s: float = Field(0.0, ge=-2.0, le=2.0,
                                    description="second vessel's horizontal speed before release [m/s]")
    payout_rate_m_s: float = Field(0.0, ge=-1.0, le=1.0,
                                   description="mooring-line winch payout rate before release [m/s]")


class CatenaryLineConfig(_Strict):
    """A single mooring line from a seabed anchor point to a fairlead (statics validation scenes)."""

    segments: tuple[tuple[str, float], ...] = Field(..., min_length=1,
                                                    description="(material, length [m]) from the anchor up")
    anchor_x_m: float = 0.0
    fairlead_x_m: float = Field(..., description="horizontal position of the fairlead [m]")
    fairlead_depth_m: float = Field(0.0, ge=0.0)


class DiscretizationConfig(_Strict):
    """Resolution and time stepping (the fidelity knobs)."""

    vertical_chain_segment_m: float = Field(1.0, ge=0.05, le=50.0)
    loop_chain_segment_m: float = Field(1.0, ge=0.05, le=50.0)
    fibre_segment_m: float = Field(5.0, ge=0.1, le=200.0)
    wire_segment_m: float = Field(10.0, ge=0.1, le=500.0)
    catenary_segment_m: float = Field(2.0, ge=0.1, le=200.0)
    integrator: Literal["symplectic_euler", "rk2", "implicit_euler"] = "symplectic_euler"
    dt_s: float | None = Field(None, gt=0.0, le=1.0,
                               description="time step [s]; None derives it from the stability limit")
    dt_safety: float = Field(0.9, gt=0.0, le=1.0,
                             description="fraction of the stability limit used when dt_s is derived")
    fall_integrator: Literal["symplectic_euler", "rk2", "implicit_euler"] | None = Field(
        None, description="integrator of the fall after the release, at dt_safety times its own limit on the mesh "
        "of the fall (e.g. symplectic_euler after an implicit pre-release phase: the explicit reference fall); "
        "None: integrator")
    fall_step_growth_max: float = Field(
        1.0, ge=1.0, le=3.0, description="an implicit_euler fall lengthens its step up to this many times where the "
        "fastest node moves slower than the 40 m/s the step's accuracy cap assumes (the cap evaluated at the "
        "fastest node's speed; it multiplies the step the fall is asked for, control.fall_dt_scale included); faster, "
        "at a measured cost in accuracy (docs/fall-accuracy.md); 1: fixed steps; the explicit integrators ignore it")
    fit_to_geometry: bool = Field(
        True, description="fit a preset's tight_line resolution to the scene's release geometry when it is loaded; "
        "the envs set false and choose it themselves, at the reset and again for the fall at the release")
    line_anchor_contact: Literal["auto", "on", "off"] = Field(
        "auto", description="contact between the lines and the anchor's body; auto: where the chain can catch up "
        "with the falling anchor (moor_env.contact_model)")
    contact_stiffness_scale: float = Field(
        1.0, gt=0.0, le=10.0, description="multiplies the line-anchor contact stiffness (convergence studies)")


class SimulationConfig(_Strict):
    """Run control."""

    max_fall_time_s: float = Field(30.0, gt=0.0, le=600.0,
                                   description="fall time after which a run without touchdown stops [s]")
    record_interval_s: float = Field(0.02, gt=0.0, le=10.0)
    snapshot_interval_s: float = Field(0.5, gt=0.0, le=60.0)
    speed_limit_m_s: float = Field(300.0, gt=0.0, description="any node faster than this is treated as a blow-up [m/s]")
    strain_limit: float = Field(0.5, gt=0.0, description="any segment strained more than this is treated as a blow-up")


class SceneConfig(_Strict):
    """A complete scene: environment, materials, anchor and what to simulate."""

    name: str
    description: str = ""
    kind: Literal["dart_installation", "catenary_line"] = "dart_installation"
    fidelity: Literal["fast", "default", "accurate", "custom"] = Field(
        "default", description="discretization preset from configs/fidelity.yaml; explicit discretization keys win")
    environment: EnvironmentConfig
    materials: dict[str, MaterialConfig]
    anchor: AnchorConfig | None = None
    release_unit: ReleaseUnitConfig = ReleaseUnitConfig()
    installation: InstallationConfig | None = None
    catenary_line: CatenaryLineConfig | None = None
    discretization: DiscretizationConfig = DiscretizationConfig()
    simulation: SimulationConfig = SimulationConfig()

    @model_validator(mode="after")
    def _check_kind(self) -> SceneConfig:
        if self.kind == "dart_installation" and (self.anchor is None or self.installation is None):
            raise ValueError("a dart_installation scene needs 'anchor' and 'installation'")
        if self.kind == "catenary_line" and self.catenary_line is None:
            raise ValueError("a catenary_line scene needs 'catenary_line'")
        return self
