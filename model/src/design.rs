//! `GenerateModel(q_D)` (the paper's Alg. 1 helper): the planar ADAM model and its URDF for any
//! thigh and shin lengths, with every link's mass, centre of mass and inertia following the
//! lengths through **cubic polynomial fits**.
//!
//! ADAM's CAD is not public. Our stand-in for it is a documented *parametric link geometry*
//! ([`thigh_properties`], [`shin_properties`]): brackets, an aluminium tube and, on the thigh, the
//! knee's A1 actuator, each a box, tube or cylinder with exact mass properties. As the paper did
//! with its CAD, we sample the geometry at [`FIT_SAMPLES`] lengths in
//! [[`DESIGN_MIN_M`], [`DESIGN_MAX_M`]] and fit a cubic in the length to each property; the model
//! uses the fits (which the planner can differentiate), and a test bounds the fit error.
//! Every number and its source is listed in `configs/robots/README.md`.

use crate::robot::PlanarModel;
use crate::{ModelError, Real, Result};
use serde::{Deserialize, Serialize};

/// Shortest thigh or shin, m (paper Table I).
pub const DESIGN_MIN_M: f64 = 0.15;
/// Longest thigh or shin, m (paper Table I).
pub const DESIGN_MAX_M: f64 = 0.35;
/// Number of lengths the geometry is sampled at for the fits.
pub const FIT_SAMPLES: usize = 9;
/// The hardware ADAM's thigh length, m (paper Sec. IV-D).
pub const ADAM_THIGH_M: f64 = 0.24;
/// The hardware ADAM's shin length, m (paper Sec. IV-D).
pub const ADAM_SHIN_M: f64 = 0.25;

/// A1 actuator: mass, kg (Unitree A1 motor datasheet: 605 g).
pub const A1_MOTOR_MASS_KG: f64 = 0.605;
/// A1 actuator housing radius, m (≈ 96 mm diameter).
pub const A1_MOTOR_RADIUS_M: f64 = 0.048;
/// A1 actuator housing width along its axis, m.
pub const A1_MOTOR_WIDTH_M: f64 = 0.045;
/// A1 output torque limit, N·m (joint side).
pub const A1_TORQUE_LIMIT_NM: f64 = 33.5;
/// A1 output speed limit, rad/s (joint side).
pub const A1_SPEED_LIMIT_RAD_S: f64 = 21.0;
/// A1 gear ratio N (Unitree A1 actuator specification: 9.1).
pub const A1_GEAR_RATIO: f64 = 9.1;
/// A1 rotor inertia about its axis (motor side), kg·m²: MuJoCo Menagerie's A1 model
/// (`unitree_a1/a1.xml`) gives the leg joints `armature="0.01"` kg·m² (joint side), which is
/// N² J_rotor, so J_rotor = 0.01 / 9.1².
pub const A1_ROTOR_INERTIA_KGM2: f64 = 0.01 / (A1_GEAR_RATIO * A1_GEAR_RATIO);
/// A1 torque constant k_t (motor side), N·m/A: 0.8372 N·m/A at the output (a public Simscape
/// model of the A1, see configs/robots/README.md) over N = 9.1; the simulator's firmware model
/// uses the same 0.092 N·m/A (40 A at the 33.5 N·m peak).
pub const A1_TORQUE_CONSTANT_NM_PER_A: f64 = 0.092;
/// A1 winding resistance R in P_cu = i² R, Ω: no public identification found; the simulator's
/// firmware model's value (its thermal model), an assumption (configs/robots/README.md).
pub const A1_WINDING_RESISTANCE_OHM: f64 = 0.25;
/// Viscous friction of the A1 joints, N·m·s/rad: no public identification found (MuJoCo
/// Menagerie's `damping="2"` is the derivative gain of its position actuators, which have no
/// `kv`, not friction), so the generated model has none; a URDF may give one per joint with
/// `<dynamics damping=…>`.
pub const A1_JOINT_DAMPING_NMS_PER_RAD: f64 = 0.0;
/// Leg tube: aluminium 6061 density, kg/m³.
pub const TUBE_DENSITY_KG_M3: f64 = 2700.0;
/// Leg tube outer radius, m (40 mm tube).
pub const TUBE_OUTER_RADIUS_M: f64 = 0.020;
/// Leg tube inner radius, m (2 mm wall).
pub const TUBE_INNER_RADIUS_M: f64 = 0.018;

/// Thigh and shin lengths: the design the co-design optimizes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignLengths {
    /// Hip axis to knee axis, m.
    pub thigh_length_m: f64,
    /// Knee axis to the foot contact point, m.
    pub shin_length_m: f64,
}

impl DesignLengths {
    /// The hardware ADAM (0.24 m / 0.25 m).
    pub const ADAM: Self = Self {
        thigh_length_m: ADAM_THIGH_M,
        shin_length_m: ADAM_SHIN_M,
    };

    /// Checks both lengths lie in [`DESIGN_MIN_M`, `DESIGN_MAX_M`].
    pub fn validate(&self) -> Result<()> {
        for (field, value) in [
            ("thigh_length_m", self.thigh_length_m),
            ("shin_length_m", self.shin_length_m),
        ] {
            if !(DESIGN_MIN_M..=DESIGN_MAX_M).contains(&value) {
                return Err(ModelError::DesignOutOfRange {
                    field,
                    value,
                    min: DESIGN_MIN_M,
                    max: DESIGN_MAX_M,
                });
            }
        }
        Ok(())
    }
}

/// Mass properties of a link in its frame (origin at the proximal joint axis, the link along −z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkMassProperties {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Distance of the centre of mass below the proximal axis, m (com = (0, 0, −d)).
    pub com_distance_m: f64,
    /// Inertia about the com, roll axis (x), kg·m².
    pub ixx_kgm2: f64,
    /// Inertia about the com, pitch axis (y), kg·m².
    pub iyy_kgm2: f64,
    /// Inertia about the com, along the link (z), kg·m².
    pub izz_kgm2: f64,
}

/// One part of a link, on the link axis.
#[derive(Clone, Copy)]
struct Part {
    mass_kg: f64,
    distance_m: f64,
    /// Own inertia about its com: (x, y, z).
    inertia: [f64; 3],
}

fn box_part(mass_kg: f64, distance_m: f64, along_m: f64, fore_aft_m: f64, lateral_m: f64) -> Part {
    let (a, b, w) = (
        along_m * along_m,
        fore_aft_m * fore_aft_m,
        lateral_m * lateral_m,
    );
    Part {
        mass_kg,
        distance_m,
        inertia: [
            mass_kg * (a + w) / 12.0,
            mass_kg * (a + b) / 12.0,
            mass_kg * (b + w) / 12.0,
        ],
    }
}

fn tube_part(from_m: f64, to_m: f64, density_scale: f64) -> Part {
    let l = to_m - from_m;
    let (ro2, ri2) = (TUBE_OUTER_RADIUS_M.powi(2), TUBE_INNER_RADIUS_M.powi(2));
    let m = density_scale * TUBE_DENSITY_KG_M3 * std::f64::consts::PI * (ro2 - ri2) * l;
    let transverse = m * (3.0 * (ro2 + ri2) + l * l) / 12.0;
    Part {
        mass_kg: m,
        distance_m: 0.5 * (from_m + to_m),
        inertia: [transverse, transverse, 0.5 * m * (ro2 + ri2)],
    }
}

fn a1_motor_part(distance_m: f64) -> Part {
    let (m, r2, w2) = (
        A1_MOTOR_MASS_KG,
        A1_MOTOR_RADIUS_M.powi(2),
        A1_MOTOR_WIDTH_M.powi(2),
    );
    let across = m * (3.0 * r2 + w2) / 12.0;
    Part {
        mass_kg: m,
        distance_m,
        inertia: [across, 0.5 * m * r2, across],
    }
}

fn combine(parts: &[Part]) -> LinkMassProperties {
    let m: f64 = parts.iter().map(|p| p.mass_kg).sum();
    let d = parts.iter().map(|p| p.mass_kg * p.distance_m).sum::<f64>() / m;
    let shift: f64 = parts
        .iter()
        .map(|p| p.mass_kg * (p.distance_m - d).powi(2))
        .sum();
    let sum = |k: usize| parts.iter().map(|p| p.inertia[k]).sum::<f64>();
    LinkMassProperties {
        mass_kg: m,
        com_distance_m: d,
        ixx_kgm2: sum(0) + shift,
        iyy_kgm2: sum(1) + shift,
        izz_kgm2: sum(2),
    }
}

/// The mass model's knobs: a scale on the leg tubes' mass per metre (their linear density,
/// 0.645 kg/m at 1), for showing how the co-design's optimum moves with heavier or lighter
/// links (the brackets, the knee's A1 and the foot do not scale); and whether the URDF carries
/// the A1 drives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassModel {
    /// Multiplies the tubes' linear density (1 = the Ø40 × 2 mm aluminium 6061 tube).
    pub link_density_scale: f64,
    /// Write the A1 drives into the URDF: `<dynamics damping>` on the hip and knee and a
    /// `<transmission>` per joint with the A1's gear ratio, rotor inertia (the armature
    /// N² J_rotor = 0.01 kg·m² at the joint), torque constant and winding resistance (what the
    /// electrical cost needs). Off by default: the shipped robot and its gaits, and the
    /// runtime's gains tuned on them, are the rigid-body model; with the armature the runtime's
    /// stand and stop tests and two fault scenarios need re-tuning (issue #28 item 4, open).
    /// `configs/robots/adam_planar_a1.urdf` is the hardware ADAM with the drives.
    pub a1_drives: bool,
}

impl Default for MassModel {
    fn default() -> Self {
        Self {
            link_density_scale: 1.0,
            a1_drives: false,
        }
    }
}

impl MassModel {
    /// The scale must be a finite number > 0.
    pub fn validate(&self) -> Result<()> {
        let v = self.link_density_scale;
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(ModelError::InvalidField {
                origin: "mass model".into(),
                field: "link_density_scale".into(),
                value: v.to_string(),
                reason: "must be a finite number > 0 (1 is the shipped tube)".into(),
            })
        }
    }
}

/// Exact mass properties of the parametric thigh of length `length_m` (hip axis to knee axis):
/// hip bracket 0.20 kg, aluminium tube from 0.05 m to L − 0.05 m, knee bracket 0.15 kg, and the
/// knee's A1 actuator (0.605 kg) on the knee axis.
pub fn thigh_properties(length_m: f64) -> LinkMassProperties {
    thigh_properties_with(length_m, &MassModel::default())
}

/// [`thigh_properties`] with the tube's density scaled by `mass`.
pub fn thigh_properties_with(length_m: f64, mass: &MassModel) -> LinkMassProperties {
    combine(&[
        box_part(0.20, 0.025, 0.05, 0.06, 0.05),
        tube_part(0.05, length_m - 0.05, mass.link_density_scale),
        box_part(0.15, length_m - 0.03, 0.04, 0.06, 0.05),
        a1_motor_part(length_m),
    ])
}

/// Exact mass properties of the parametric shin of length `length_m` (knee axis to foot point),
/// the foot excluded: knee output horn 0.12 kg, tube from 0.05 m to L − 0.02 m, ankle cap 0.04 kg.
pub fn shin_properties(length_m: f64) -> LinkMassProperties {
    shin_properties_with(length_m, &MassModel::default())
}

/// [`shin_properties`] with the tube's density scaled by `mass`.
pub fn shin_properties_with(length_m: f64, mass: &MassModel) -> LinkMassProperties {
    combine(&[
        box_part(0.12, 0.025, 0.05, 0.05, 0.04),
        tube_part(0.05, length_m - 0.02, mass.link_density_scale),
        box_part(0.04, length_m - 0.015, 0.02, 0.03, 0.03),
    ])
}

/// The foot (a rubber ball of radius 2 cm, 0.06 kg) in its frame at the contact point:
/// (mass, com height above the contact point, inertia about its com).
pub const FOOT: (f64, f64, f64) = (0.06, 0.015, 0.4 * 0.06 * 0.02 * 0.02);

/// A cubic in the link length, stored in the centred variable s = (L − 0.25 m) / 0.1 m for
/// conditioning: p(L) = c0 + c1 s + c2 s² + c3 s³.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cubic(pub [f64; 4]);

impl Cubic {
    const CENTER_M: f64 = 0.25;
    const SCALE_M: f64 = 0.1;

    /// Evaluates the fit at `length_m`, generic so the planner can differentiate it.
    pub fn eval<S: Real>(&self, length_m: S) -> S {
        let s = (length_m - Self::CENTER_M) / Self::SCALE_M;
        ((s * self.0[3] + self.0[2]) * s + self.0[1]) * s + self.0[0]
    }

    /// Least-squares cubic through the samples.
    pub fn fit(lengths_m: &[f64], values: &[f64]) -> Self {
        let n = lengths_m.len();
        let a = nalgebra::DMatrix::from_fn(n, 4, |r, c| {
            ((lengths_m[r] - Self::CENTER_M) / Self::SCALE_M).powi(c as i32)
        });
        let b = nalgebra::DVector::from_column_slice(values);
        // Normal equations of a 4-column Vandermonde in a centred variable are well conditioned.
        let ata = a.transpose() * &a;
        let atb = a.transpose() * b;
        let x = ata
            .lu()
            .solve(&atb)
            .unwrap_or_else(|| nalgebra::DVector::zeros(4));
        Self([x[0], x[1], x[2], x[3]])
    }
}

/// Cubic fits of one link's mass properties against its length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkFit {
    /// Mass, kg.
    pub mass_kg: Cubic,
    /// Com distance below the proximal axis, m.
    pub com_distance_m: Cubic,
    /// I_xx about the com, kg·m².
    pub ixx_kgm2: Cubic,
    /// I_yy about the com, kg·m².
    pub iyy_kgm2: Cubic,
    /// I_zz about the com, kg·m².
    pub izz_kgm2: Cubic,
}

impl LinkFit {
    /// Fits `geometry` sampled at `lengths_m`.
    pub fn fit(geometry: impl Fn(f64) -> LinkMassProperties, lengths_m: &[f64]) -> Self {
        let samples: Vec<LinkMassProperties> = lengths_m.iter().map(|&l| geometry(l)).collect();
        let f = |get: fn(&LinkMassProperties) -> f64| {
            Cubic::fit(lengths_m, &samples.iter().map(get).collect::<Vec<_>>())
        };
        Self {
            mass_kg: f(|p| p.mass_kg),
            com_distance_m: f(|p| p.com_distance_m),
            ixx_kgm2: f(|p| p.ixx_kgm2),
            iyy_kgm2: f(|p| p.iyy_kgm2),
            izz_kgm2: f(|p| p.izz_kgm2),
        }
    }

    /// The fitted properties at `length_m`.
    pub fn at(&self, length_m: f64) -> LinkMassProperties {
        LinkMassProperties {
            mass_kg: self.mass_kg.eval(length_m),
            com_distance_m: self.com_distance_m.eval(length_m),
            ixx_kgm2: self.ixx_kgm2.eval(length_m),
            iyy_kgm2: self.iyy_kgm2.eval(length_m),
            izz_kgm2: self.izz_kgm2.eval(length_m),
        }
    }

    /// Largest relative error of the fit against `geometry` over `n` evenly spaced lengths in the
    /// design range, over all five properties.
    pub fn max_relative_error(
        &self,
        geometry: impl Fn(f64) -> LinkMassProperties,
        n: usize,
    ) -> f64 {
        (0..n)
            .map(|i| DESIGN_MIN_M + (DESIGN_MAX_M - DESIGN_MIN_M) * i as f64 / (n - 1) as f64)
            .map(|l| {
                let (e, f) = (geometry(l), self.at(l));
                [
                    (e.mass_kg, f.mass_kg),
                    (e.com_distance_m, f.com_distance_m),
                    (e.ixx_kgm2, f.ixx_kgm2),
                    (e.iyy_kgm2, f.iyy_kgm2),
                    (e.izz_kgm2, f.izz_kgm2),
                ]
                .iter()
                .map(|(a, b)| ((a - b) / a).abs())
                .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max)
    }
}

/// The inertia fits of ADAM's thigh and shin.
#[derive(Clone, Debug, PartialEq)]
pub struct InertiaFits {
    /// Sample lengths, m.
    pub sample_lengths_m: Vec<f64>,
    /// Thigh fit.
    pub thigh: LinkFit,
    /// Shin fit.
    pub shin: LinkFit,
}

impl InertiaFits {
    /// Samples the parametric geometry at [`FIT_SAMPLES`] evenly spaced lengths and fits cubics.
    pub fn adam() -> Self {
        Self::adam_with(&MassModel::default())
    }

    /// [`Self::adam`] for the mass model `mass` (scaled tube density).
    pub fn adam_with(mass: &MassModel) -> Self {
        let sample_lengths_m: Vec<f64> = (0..FIT_SAMPLES)
            .map(|i| {
                DESIGN_MIN_M + (DESIGN_MAX_M - DESIGN_MIN_M) * i as f64 / (FIT_SAMPLES - 1) as f64
            })
            .collect();
        Self {
            thigh: LinkFit::fit(|l| thigh_properties_with(l, mass), &sample_lengths_m),
            shin: LinkFit::fit(|l| shin_properties_with(l, mass), &sample_lengths_m),
            sample_lengths_m,
        }
    }
}

/// Torso parts lumped into one rigid body: (name, mass kg, centre height above the hip axis m,
/// box extent along z, x, y in m). The A1 trunk stands upright above the hip yaw/roll stack; the
/// arms (3 A1 actuators each plus links) hang beside it, held still during planar walking.
pub const TORSO_PARTS: [(&str, f64, f64, [f64; 3]); 3] = [
    (
        "A1 trunk (battery and computer inside)",
        6.0,
        0.2335,
        [0.267, 0.114, 0.194],
    ),
    (
        "hip yaw and roll A1 actuators with brackets (4 x 0.75 kg)",
        3.0,
        0.05,
        [0.10, 0.10, 0.20],
    ),
    (
        "arms, 3 A1 actuators and links each (2 x 2.165 kg)",
        4.33,
        0.23,
        [0.28, 0.05, 0.36],
    ),
];

/// Lumped torso: (mass, com height above the hip axis, ixx, iyy, izz about the com).
pub fn torso_properties() -> (f64, f64, [f64; 3]) {
    let m: f64 = TORSO_PARTS.iter().map(|p| p.1).sum();
    let h = TORSO_PARTS.iter().map(|p| p.1 * p.2).sum::<f64>() / m;
    let mut i = [0.0; 3];
    for &(_, mp, hp, [ez, ex, ey]) in &TORSO_PARTS {
        let shift = mp * (hp - h).powi(2);
        i[0] += mp * (ez * ez + ey * ey) / 12.0 + shift;
        i[1] += mp * (ez * ez + ex * ex) / 12.0 + shift;
        i[2] += mp * (ex * ex + ey * ey) / 12.0;
    }
    (m, h, i)
}

/// Hip pitch range, rad (positive swings the leg backwards).
pub const HIP_PITCH_LIMITS_RAD: (f64, f64) = (-1.6, 1.6);
/// Knee pitch range, rad (positive flexes the knee; 0 is a straight leg).
pub const KNEE_PITCH_LIMITS_RAD: (f64, f64) = (0.0, 2.4);
/// Lateral hip offset, m (written to the URDF, ignored by the planar model).
pub const HIP_LATERAL_OFFSET_M: f64 = 0.09;

/// The URDF text of the planar ADAM with the given thigh and shin lengths, link inertials from the
/// cubic fits, and design virtual joints at zero whose limits keep each length in the design range.
pub fn generate_urdf(design: &DesignLengths) -> Result<String> {
    generate_urdf_with(design, &MassModel::default())
}

/// [`generate_urdf`] for the mass model `mass` (its header names a scale other than 1).
pub fn generate_urdf_with(design: &DesignLengths, mass: &MassModel) -> Result<String> {
    design.validate()?;
    mass.validate()?;
    let fits = InertiaFits::adam_with(mass);
    let damping = if mass.a1_drives {
        format!("    <dynamics damping=\"{A1_JOINT_DAMPING_NMS_PER_RAD}\"/>\n")
    } else {
        String::new()
    };
    let (tm, th, ti) = torso_properties();
    let (fm, fh, fi) = FOOT;
    let mut s = String::new();
    s.push_str(&format!(
        "<?xml version=\"1.0\"?>\n<!-- Planar point-foot ADAM for treadmill-boom walking. GENERATED by model::design::generate_urdf (the command adam generate-urdf) for thigh {t} m and shin {sh} m{scale}: do not edit by hand. Sources of every number: configs/robots/README.md. -->\n<robot name=\"adam_planar\">\n",
        t = design.thigh_length_m,
        sh = design.shin_length_m,
        scale = if mass.link_density_scale == 1.0 {
            String::new()
        } else {
            format!(" with the leg tubes' density scaled by {}", mass.link_density_scale)
        }
    ));
    s.push_str(&format!(
        "  <link name=\"torso\">\n    <inertial>\n      <origin xyz=\"0 0 {th}\" rpy=\"0 0 0\"/>\n      <mass value=\"{tm}\"/>\n      <inertia ixx=\"{}\" ixy=\"0\" ixz=\"0\" iyy=\"{}\" iyz=\"0\" izz=\"{}\"/>\n    </inertial>\n  </link>\n",
        ti[0], ti[1], ti[2]
    ));
    let inertial = |p: &LinkMassProperties| {
        format!(
            "    <inertial>\n      <origin xyz=\"0 0 {}\" rpy=\"0 0 0\"/>\n      <mass value=\"{}\"/>\n      <inertia ixx=\"{}\" ixy=\"0\" ixz=\"0\" iyy=\"{}\" iyz=\"0\" izz=\"{}\"/>\n    </inertial>\n",
            -p.com_distance_m, p.mass_kg, p.ixx_kgm2, p.iyy_kgm2, p.izz_kgm2
        )
    };
    let massless = "    <inertial>\n      <mass value=\"0\"/>\n      <inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/>\n    </inertial>\n";
    let thigh = fits.thigh.at(design.thigh_length_m);
    let shin = fits.shin.at(design.shin_length_m);
    for (side, y) in [
        ("left", HIP_LATERAL_OFFSET_M),
        ("right", -HIP_LATERAL_OFFSET_M),
    ] {
        let (lt, ls) = (design.thigh_length_m, design.shin_length_m);
        s.push_str(&format!(
            "  <link name=\"{side}_thigh\">\n{}  </link>\n",
            inertial(&thigh)
        ));
        s.push_str(&format!(
            "  <link name=\"{side}_thigh_virtual\">\n{massless}  </link>\n"
        ));
        s.push_str(&format!(
            "  <link name=\"{side}_shin\">\n{}  </link>\n",
            inertial(&shin)
        ));
        s.push_str(&format!(
            "  <link name=\"{side}_shin_virtual\">\n{massless}  </link>\n"
        ));
        s.push_str(&format!(
            "  <link name=\"{side}_foot\">\n    <inertial>\n      <origin xyz=\"0 0 {fh}\" rpy=\"0 0 0\"/>\n      <mass value=\"{fm}\"/>\n      <inertia ixx=\"{fi}\" ixy=\"0\" ixz=\"0\" iyy=\"{fi}\" iyz=\"0\" izz=\"{fi}\"/>\n    </inertial>\n  </link>\n"
        ));
        let (hl, hu) = HIP_PITCH_LIMITS_RAD;
        let (kl, ku) = KNEE_PITCH_LIMITS_RAD;
        s.push_str(&format!(
            "  <joint name=\"{side}_hip_pitch\" type=\"revolute\">\n    <parent link=\"torso\"/>\n    <child link=\"{side}_thigh\"/>\n    <origin xyz=\"0 {y} 0\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0 1 0\"/>\n{damping}    <limit lower=\"{hl}\" upper=\"{hu}\" effort=\"{A1_TORQUE_LIMIT_NM}\" velocity=\"{A1_SPEED_LIMIT_RAD_S}\"/>\n  </joint>\n"
        ));
        s.push_str(&format!(
            "  <joint name=\"{side}_thigh_design\" type=\"prismatic\">\n    <parent link=\"{side}_thigh\"/>\n    <child link=\"{side}_thigh_virtual\"/>\n    <origin xyz=\"0 0 {}\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0 0 -1\"/>\n    <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>\n  </joint>\n",
            -lt,
            DESIGN_MIN_M - lt,
            DESIGN_MAX_M - lt
        ));
        s.push_str(&format!(
            "  <joint name=\"{side}_knee_pitch\" type=\"revolute\">\n    <parent link=\"{side}_thigh_virtual\"/>\n    <child link=\"{side}_shin\"/>\n    <origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0 1 0\"/>\n{damping}    <limit lower=\"{kl}\" upper=\"{ku}\" effort=\"{A1_TORQUE_LIMIT_NM}\" velocity=\"{A1_SPEED_LIMIT_RAD_S}\"/>\n  </joint>\n"
        ));
        s.push_str(&format!(
            "  <joint name=\"{side}_shin_design\" type=\"prismatic\">\n    <parent link=\"{side}_shin\"/>\n    <child link=\"{side}_shin_virtual\"/>\n    <origin xyz=\"0 0 {}\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0 0 -1\"/>\n    <limit lower=\"{}\" upper=\"{}\" effort=\"0\" velocity=\"0\"/>\n  </joint>\n",
            -ls,
            DESIGN_MIN_M - ls,
            DESIGN_MAX_M - ls
        ));
        s.push_str(&format!(
            "  <joint name=\"{side}_foot_fixed\" type=\"fixed\">\n    <parent link=\"{side}_shin_virtual\"/>\n    <child link=\"{side}_foot\"/>\n    <origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n  </joint>\n"
        ));
    }
    for side in ["left", "right"] {
        for joint in ["hip_pitch", "knee_pitch"] {
            if mass.a1_drives {
                s.push_str(&a1_transmission(&format!("{side}_{joint}")));
            }
        }
    }
    s.push_str("</robot>\n");
    Ok(s)
}

/// The `<transmission>` of an A1 driving `joint` (the format of [`crate::urdf`]).
fn a1_transmission(joint: &str) -> String {
    format!(
        "  <transmission name=\"{joint}_a1\">\n    <type>transmission_interface/SimpleTransmission</type>\n    <joint name=\"{joint}\"/>\n    <actuator name=\"{joint}_motor\">\n      <mechanicalReduction>{A1_GEAR_RATIO}</mechanicalReduction>\n      <rotorInertia>{A1_ROTOR_INERTIA_KGM2}</rotorInertia>\n      <torqueConstant>{A1_TORQUE_CONSTANT_NM_PER_A}</torqueConstant>\n      <windingResistance>{A1_WINDING_RESISTANCE_OHM}</windingResistance>\n    </actuator>\n  </transmission>\n"
    )
}

/// `GenerateModel(q_D)`: the planar model and its URDF text for the given design.
pub fn generate_model(design: &DesignLengths) -> Result<(PlanarModel, String)> {
    generate_model_with(design, &MassModel::default())
}

/// [`generate_model`] for the mass model `mass`.
pub fn generate_model_with(
    design: &DesignLengths,
    mass: &MassModel,
) -> Result<(PlanarModel, String)> {
    let text = generate_urdf_with(design, mass)?;
    let model = PlanarModel::from_urdf_str(&text, "<generated>")?;
    Ok((model, text))
}
