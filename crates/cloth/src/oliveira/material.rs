//! Material properties and the particle and spring parameters derived from them (Oliveira 2013 §4.3).

use serde::{Deserialize, Serialize};

/// Cloth material (Oliveira 2013 §4.3.1, Tables 5.1, 5.3, 5.5). Every particle and spring parameter is
/// derived from these, so the same material on a finer mesh gets lighter particles and stiffer springs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// ρ, kg/m³.
    pub density_kg_m3: f64,
    /// T, m.
    pub thickness_m: f64,
    /// κ: air drag per unit area, kg/(m²·s) (C_i = A_i·κ, Eq. 4.2).
    pub permeability: f64,
    /// E, N/m².
    pub young_modulus_pa: f64,
    /// A⁰, the spring cross-section of Eq. 4.3, m². The thesis calls it an input but prints no value;
    /// the spec infers 2.5 × 10⁻⁶ m² from the frame counts (§7.5, Q-1).
    pub cross_section_m2: f64,
    /// α, spring damping as a fraction of stiffness (k^d = α·k^e, Eq. 4.4); the tables print 1 %.
    pub damping_ratio: f64,
    /// k^e_flexão of Eq. 4.11, used as printed (the tables say "N/m"; Bridson's formula implies N·m, Q-3).
    pub bending_stiffness: f64,
    /// k^d_flexão of Eq. 4.13, used as printed ("N/m"; N·s by dimensions, Q-3).
    pub bending_damping: f64,
    /// μ of the cloth; a contact uses the mean of the cloth's and the object's (Eq. 4.17).
    pub friction: f64,
}

/// The spring cross-section the spec infers from the thesis's frame counts (§7.5).
pub const DEFAULT_CROSS_SECTION_M2: f64 = 2.5e-6;

impl Material {
    /// Table 5.1 (Test I, the Stanford Bunny) and Table 5.3 differ only in κ; Table 5.5 in ρ and μ.
    pub const fn table_5_1() -> Self {
        Self {
            density_kg_m3: 8.0e3,
            thickness_m: 1.0e-4,
            permeability: 3.0,
            young_modulus_pa: 1.0e7,
            cross_section_m2: DEFAULT_CROSS_SECTION_M2,
            damping_ratio: 0.01,
            bending_stiffness: 1.0e-3,
            bending_damping: 1.0e-4,
            friction: 0.4,
        }
    }

    /// Table 5.3 (Test II, the round table).
    pub const fn table_5_3() -> Self {
        Self { permeability: 3.5, ..Self::table_5_1() }
    }

    /// Table 5.5 (Test III, the sphere).
    pub const fn table_5_5() -> Self {
        Self { density_kg_m3: 6.0e3, friction: 0.05, ..Self::table_5_1() }
    }

    /// Mass per unit area ρ·T, kg/m².
    pub fn areal_density(&self) -> f64 {
        self.density_kg_m3 * self.thickness_m
    }

    /// m_i = A_i·T·ρ (Eq. 4.1), kg, for an area of influence A_i in m².
    pub fn particle_mass(&self, area_m2: f64) -> f64 {
        area_m2 * self.thickness_m * self.density_kg_m3
    }

    /// C_i = A_i·κ (Eq. 4.2), kg/s.
    pub fn particle_drag(&self, area_m2: f64) -> f64 {
        area_m2 * self.permeability
    }

    /// k^e = E·A⁰/L⁰ (Eq. 4.3), N/m.
    pub fn spring_stiffness(&self, rest_length_m: f64) -> f64 {
        self.young_modulus_pa * self.cross_section_m2 / rest_length_m
    }

    /// k^d = α·k^e (Eq. 4.4), N·s/m.
    pub fn spring_damping(&self, rest_length_m: f64) -> f64 {
        self.damping_ratio * self.spring_stiffness(rest_length_m)
    }

    /// The first parameter that is not a finite number in its allowed range, named as in the scene file.
    pub fn invalid_field(&self) -> Option<&'static str> {
        let positive = [
            ("density_kg_m3", self.density_kg_m3),
            ("thickness_m", self.thickness_m),
            ("young_modulus_pa", self.young_modulus_pa),
            ("cross_section_m2", self.cross_section_m2),
        ];
        let non_negative = [
            ("permeability", self.permeability),
            ("damping_ratio", self.damping_ratio),
            ("bending_stiffness", self.bending_stiffness),
            ("bending_damping", self.bending_damping),
            ("friction", self.friction),
        ];
        positive
            .iter()
            .find(|(_, v)| !(v.is_finite() && *v > 0.0))
            .or_else(|| non_negative.iter().find(|(_, v)| !(v.is_finite() && *v >= 0.0)))
            .map(|(name, _)| *name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derived_parameters_match_the_spec_numbers() {
        let m = Material::table_5_1();
        // Spec §7.5: the coarse grid's one-triangle corner (area 0.0104 m²) weighs 8.33 × 10⁻³ kg; the fine
        // grid's 5.21 × 10⁻⁴ kg; a 0.25 m spring has k = 100 N/m, a 0.0625 m spring 400 N/m.
        assert!((m.particle_mass(0.0625 / 6.0) - 8.333e-3).abs() < 1e-6);
        assert!((m.particle_mass(0.0625 * 0.0625 / 6.0) - 5.208e-4).abs() < 1e-6);
        assert!((m.spring_stiffness(0.25) - 100.0).abs() < 1e-9);
        assert!((m.spring_stiffness(0.0625) - 400.0).abs() < 1e-9);
        assert!((m.spring_damping(0.25) - 1.0).abs() < 1e-12);
        // Mesh-independent drag time constant ρT/κ (spec §4.2): 0.267 s, 0.229 s, 0.200 s.
        for (mat, tau) in
            [(Material::table_5_1(), 0.2667), (Material::table_5_3(), 0.2286), (Material::table_5_5(), 0.2)]
        {
            assert!((mat.particle_mass(0.3) / mat.particle_drag(0.3) - tau).abs() < 1e-4);
        }
        assert_eq!(m.invalid_field(), None);
        assert_eq!(Material { young_modulus_pa: -1.0, ..m }.invalid_field(), Some("young_modulus_pa"));
        assert_eq!(Material { friction: f64::NAN, ..m }.invalid_field(), Some("friction"));
    }
}
