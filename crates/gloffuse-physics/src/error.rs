//! The physics' own error: a value that no BSDF or table here can take. The library wraps it
//! (its `Error` converts each [`Quantity`] to the input field the user set), so this crate
//! knows nothing of flags, files or Blender runs.

/// A quantity of the physics, as its messages name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// The Anisotropy input of a Glossy BSDF.
    Anisotropy,
    /// The Blender version whose BSDFs are modelled.
    BlenderVersion,
    /// A microfacet distribution.
    Distribution,
    /// A render engine (whose BSDFs differ).
    Engine,
    /// A classic BRDF model.
    Model,
    /// A parameter of a classic BRDF model, named as the model names it.
    ModelParameter(&'static str),
    /// A roughness, or a lobe width α.
    Roughness,
    /// A view cosine μ.
    ViewCosine,
}

impl Quantity {
    /// The quantity in words.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Anisotropy => "anisotropy",
            Quantity::BlenderVersion => "Blender version",
            Quantity::Distribution => "distribution",
            Quantity::Engine => "engine",
            Quantity::Model => "model",
            Quantity::ModelParameter(name) => name,
            Quantity::Roughness => "roughness",
            Quantity::ViewCosine => "view cosine mu",
        }
    }
}

/// `quantity` was given as `value`; `expected` says what would be right.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("invalid {} '{value}': expected {expected}", quantity.name())]
pub struct Error {
    pub quantity: Quantity,
    pub value: String,
    pub expected: String,
}

impl Error {
    pub fn input(quantity: Quantity, value: impl ToString, expected: impl Into<String>) -> Self {
        Error {
            quantity,
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_names_the_quantity_the_value_and_what_was_expected() {
        let e = Error::input(Quantity::Roughness, 1.5, "a number from 0 to 1");
        assert_eq!(
            e.to_string(),
            "invalid roughness '1.5': expected a number from 0 to 1"
        );
        let e = Error::input(Quantity::ModelParameter("Phong exponent n"), -1, "≥ 0");
        assert_eq!(e.to_string(), "invalid Phong exponent n '-1': expected ≥ 0");
    }
}
