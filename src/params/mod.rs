//! Parameter lists (`"type name" value` or `"type name" [ values ]`) with used-tracking.
//!
//! ```text
//! Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]
//! Material "diffuse" "rgb reflectance" [ 0.8 0.2 0.2 ]
//! Material "conductor" "spectrum eta" "metal-Au-eta" "bool remaproughness" false
//! ```
//!
//! Every parameter keeps where it was written. The getters take `&mut self` and mark what they
//! read (plain `bool`s, so a `ParamSet` stays `Send + Sync`); [`ParamSet::check_unused`] then
//! reports the first parameter nobody read, because a scene must not silently render as
//! something other than what it says. Asking for a parameter with the wrong type or number of
//! values is an error at the parameter's location.

use crate::math::{Vec2, Vec3};
mod error;

pub use error::{clip_for_message, one_line, Loc, SceneError, MAX_LINE, MAX_MESSAGE, MAX_TOKEN};

/// What a texture is told where photon does not take one (materials take them where pbrt-v4
/// does; a light's or a shape's other parameters, `"texture normalmap"`, plymesh displacement).
pub const TEXTURE_NOT_HERE: &str = "a texture is not supported for this parameter";

/// The type of a parameter, as declared by the first word of `"type name"` (aliases folded:
/// `point` is `point3`, `vector` is `vector3`, `normal3` is `normal`, `color` is `rgb`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamType {
    Integer,
    Float,
    Point2,
    Vector2,
    Point3,
    Vector3,
    Normal,
    Rgb,
    Spectrum,
    Bool,
    String,
    Texture,
    Blackbody,
}

impl ParamType {
    /// Parses a type word of a parameter declaration; `None` when unknown.
    pub fn from_name(s: &str) -> Option<ParamType> {
        Some(match s {
            "integer" => ParamType::Integer,
            "float" => ParamType::Float,
            "point2" => ParamType::Point2,
            "vector2" => ParamType::Vector2,
            "point3" | "point" => ParamType::Point3,
            "vector3" | "vector" => ParamType::Vector3,
            "normal" | "normal3" => ParamType::Normal,
            "rgb" | "color" => ParamType::Rgb,
            "spectrum" => ParamType::Spectrum,
            "bool" => ParamType::Bool,
            "string" => ParamType::String,
            "texture" => ParamType::Texture,
            "blackbody" => ParamType::Blackbody,
            _ => return None,
        })
    }

    /// The canonical pbrt-v4 name of the type.
    pub fn name(self) -> &'static str {
        match self {
            ParamType::Integer => "integer",
            ParamType::Float => "float",
            ParamType::Point2 => "point2",
            ParamType::Vector2 => "vector2",
            ParamType::Point3 => "point3",
            ParamType::Vector3 => "vector3",
            ParamType::Normal => "normal",
            ParamType::Rgb => "rgb",
            ParamType::Spectrum => "spectrum",
            ParamType::Bool => "bool",
            ParamType::String => "string",
            ParamType::Texture => "texture",
            ParamType::Blackbody => "blackbody",
        }
    }

    /// How many numbers make one value of this type (0 for non-numeric types).
    pub fn arity(self) -> usize {
        match self {
            ParamType::Integer | ParamType::Float => 1,
            ParamType::Point2 | ParamType::Vector2 => 2,
            ParamType::Point3 | ParamType::Vector3 | ParamType::Normal | ParamType::Rgb => 3,
            ParamType::Blackbody => 1,
            ParamType::Spectrum | ParamType::Bool | ParamType::String | ParamType::Texture => 0,
        }
    }
}

/// The values of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValues {
    /// Floating-point numbers (every numeric type but `integer`; spectra given as numbers).
    Floats(Vec<f32>),
    Ints(Vec<i32>),
    Bools(Vec<bool>),
    /// Strings (`string`, `texture`, named `spectrum`).
    Strings(Vec<String>),
}

impl ParamValues {
    /// How many scalars there are.
    pub fn len(&self) -> usize {
        match self {
            ParamValues::Floats(v) => v.len(),
            ParamValues::Ints(v) => v.len(),
            ParamValues::Bools(v) => v.len(),
            ParamValues::Strings(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One parameter as written in the file.
#[derive(Clone, Debug)]
pub struct Param {
    pub ty: ParamType,
    /// The type word as written (`"color"`, `"point"`, ...), for messages.
    pub ty_name: String,
    pub name: String,
    pub values: ParamValues,
    /// Where the `"type name"` string starts.
    pub loc: Loc,
    used: bool,
}

impl Param {
    /// Creates a parameter (not yet used).
    pub fn new(ty: ParamType, ty_name: &str, name: &str, values: ParamValues, loc: Loc) -> Self {
        Param {
            ty,
            ty_name: ty_name.to_string(),
            name: name.to_string(),
            values,
            loc,
            used: false,
        }
    }

    /// `"type name"` as written.
    pub fn decl(&self) -> String {
        format!("\"{} {}\"", self.ty_name, self.name)
    }

    /// An error at this parameter.
    pub fn err(&self, msg: impl std::fmt::Display) -> SceneError {
        SceneError::at(&self.loc, format!("parameter {}: {msg}", self.decl()))
    }

    /// The numbers, if numeric.
    pub fn floats(&self) -> Option<&[f32]> {
        match &self.values {
            ParamValues::Floats(v) => Some(v),
            _ => None,
        }
    }

    /// The strings, if any.
    pub fn strings(&self) -> Option<&[String]> {
        match &self.values {
            ParamValues::Strings(v) => Some(v),
            _ => None,
        }
    }
}

/// A parameter list as written in the file, with each parameter's location; reading a
/// parameter marks it used, and `check_unused` reports the ones nobody read.
#[derive(Clone, Debug, Default)]
pub struct ParamSet {
    params: Vec<Param>,
}

impl ParamSet {
    pub fn new() -> Self {
        ParamSet::default()
    }

    /// Adds a parameter; a second parameter of the same name is an error at the second one.
    pub fn push(&mut self, p: Param) -> Result<(), SceneError> {
        if let Some(first) = self.params.iter().find(|q| q.name == p.name) {
            return Err(p.err(format!("given twice (first at line {})", first.loc.line)));
        }
        self.params.push(p);
        Ok(())
    }

    pub fn len(&self) -> usize {
        self.params.len()
    }

    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameters in the order written (for tools that rewrite them, `photon upgrade`).
    pub fn into_vec(self) -> Vec<Param> {
        self.params
    }

    /// All parameters in the order written.
    pub fn iter(&self) -> impl Iterator<Item = &Param> {
        self.params.iter()
    }

    /// Whether a parameter of this name was given (does not mark it used).
    pub fn has(&self, name: &str) -> bool {
        self.params.iter().any(|p| p.name == name)
    }

    /// The parameter of this name without marking it used.
    pub fn peek(&self, name: &str) -> Option<&Param> {
        self.params.iter().find(|p| p.name == name)
    }

    /// The parameter of this name, marked used (the caller takes responsibility for its type).
    pub fn get_param(&mut self, name: &str) -> Option<&Param> {
        let p = self.params.iter_mut().find(|p| p.name == name)?;
        p.used = true;
        Some(p)
    }

    /// Where the parameter of this name was written.
    pub fn loc(&self, name: &str) -> Option<&Loc> {
        self.peek(name).map(|p| &p.loc)
    }

    /// The first parameter nobody read, as an error at its location (a texture-valued one says
    /// that no texture is supported there).
    pub fn check_unused(&self) -> Result<(), SceneError> {
        match self.params.iter().find(|p| !p.used) {
            Some(p) if p.ty == ParamType::Texture => Err(p.err(TEXTURE_NOT_HERE)),
            Some(p) => Err(SceneError::at(
                &p.loc,
                format!("unused parameter {}", p.decl()),
            )),
            None => Ok(()),
        }
    }

    /// Marks and returns the parameter `name` after checking its type is one of `types`.
    fn typed(&mut self, name: &str, types: &[ParamType]) -> Result<Option<&Param>, SceneError> {
        let Some(p) = self.get_param(name) else {
            return Ok(None);
        };
        if types.contains(&p.ty) {
            return Ok(Some(p));
        }
        let want: Vec<&str> = types.iter().map(|t| t.name()).collect();
        let why = match p.ty {
            ParamType::Texture => TEXTURE_NOT_HERE.to_string(),
            ParamType::Blackbody => {
                "blackbody spectra are only supported for light emission (\"L\", \"I\")".to_string()
            }
            ParamType::Spectrum if types.contains(&ParamType::Rgb) => {
                "spectrum values are not supported here (give an rgb)".to_string()
            }
            _ => format!("wrong type, expected {}", want.join(" or ")),
        };
        Err(p.err(why))
    }

    /// The numbers of a numeric parameter of one of `types`, checked to be a whole number of
    /// values of `arity` numbers each.
    fn numbers(
        &mut self,
        name: &str,
        types: &[ParamType],
        arity: usize,
    ) -> Result<Option<&[f32]>, SceneError> {
        let Some(p) = self.typed(name, types)? else {
            return Ok(None);
        };
        let Some(v) = p.floats() else {
            return Err(p.err("expected numbers"));
        };
        if v.len() % arity != 0 {
            return Err(p.err(format!(
                "expected a multiple of {arity} numbers, got {}",
                v.len()
            )));
        }
        Ok(Some(v))
    }

    /// Exactly `n` numbers of a numeric parameter, or `None` when absent.
    fn exactly(
        &mut self,
        name: &str,
        types: &[ParamType],
        n: usize,
    ) -> Result<Option<Vec<f32>>, SceneError> {
        let Some(v) = self.numbers(name, types, 1)? else {
            return Ok(None);
        };
        if v.len() != n {
            let len = v.len();
            let p = self.peek(name).expect("parameter was just found");
            let what = if n == 1 { "value" } else { "numbers" };
            return Err(p.err(format!("expected {n} {what}, got {len}")));
        }
        Ok(Some(v.to_vec()))
    }

    /// `"float name" value`, or `default` when absent.
    pub fn get_float(&mut self, name: &str, default: f32) -> Result<f32, SceneError> {
        Ok(self.get_float_opt(name)?.unwrap_or(default))
    }

    /// `"float name" value`, or `None` when absent.
    pub fn get_float_opt(&mut self, name: &str) -> Result<Option<f32>, SceneError> {
        Ok(self.exactly(name, &[ParamType::Float], 1)?.map(|v| v[0]))
    }

    /// `"blackbody name" [ T ]`: the temperature, or `None` when absent.
    pub fn get_blackbody(&mut self, name: &str) -> Result<Option<f32>, SceneError> {
        Ok(self
            .exactly(name, &[ParamType::Blackbody], 1)?
            .map(|v| v[0]))
    }

    /// `"integer name" value`, or `default` when absent.
    pub fn get_int(&mut self, name: &str, default: i32) -> Result<i32, SceneError> {
        let Some(p) = self.typed(name, &[ParamType::Integer])? else {
            return Ok(default);
        };
        match &p.values {
            ParamValues::Ints(v) if v.len() == 1 => Ok(v[0]),
            ParamValues::Ints(v) => Err(p.err(format!("expected 1 value, got {}", v.len()))),
            _ => Err(p.err("expected integers")),
        }
    }

    /// `"bool name" value` (`true`/`false`, quoted or bare), or `default` when absent.
    pub fn get_bool(&mut self, name: &str, default: bool) -> Result<bool, SceneError> {
        let Some(p) = self.typed(name, &[ParamType::Bool])? else {
            return Ok(default);
        };
        match &p.values {
            ParamValues::Bools(v) if v.len() == 1 => Ok(v[0]),
            ParamValues::Bools(v) => Err(p.err(format!("expected 1 value, got {}", v.len()))),
            _ => Err(p.err("expected true or false")),
        }
    }

    /// `"string name" value`, or `None` when absent.
    pub fn get_string_opt(&mut self, name: &str) -> Result<Option<String>, SceneError> {
        let Some(p) = self.typed(name, &[ParamType::String])? else {
            return Ok(None);
        };
        match &p.values {
            ParamValues::Strings(v) if v.len() == 1 => Ok(Some(v[0].clone())),
            ParamValues::Strings(v) => Err(p.err(format!("expected 1 value, got {}", v.len()))),
            _ => Err(p.err("expected a string")),
        }
    }

    /// `"string name" value`, or `default` when absent.
    pub fn get_string(&mut self, name: &str, default: &str) -> Result<String, SceneError> {
        Ok(self
            .get_string_opt(name)?
            .unwrap_or_else(|| default.to_string()))
    }

    /// `"rgb name" [r g b]` (or `color`), or `None` when absent.
    pub fn get_rgb_opt(&mut self, name: &str) -> Result<Option<Vec3>, SceneError> {
        Ok(self
            .exactly(name, &[ParamType::Rgb], 3)?
            .map(|v| Vec3::new(v[0], v[1], v[2])))
    }

    /// `"rgb name" [r g b]`, or `default` when absent.
    pub fn get_rgb(&mut self, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        Ok(self.get_rgb_opt(name)?.unwrap_or(default))
    }

    /// `"point3 name" [x y z]`, or `default` when absent.
    pub fn get_point3(&mut self, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        Ok(self
            .exactly(name, &[ParamType::Point3], 3)?
            .map_or(default, |v| Vec3::new(v[0], v[1], v[2])))
    }

    /// All numbers of `"float name" [...]`, or `None` when absent.
    pub fn get_floats(&mut self, name: &str) -> Result<Option<Vec<f32>>, SceneError> {
        Ok(self
            .numbers(name, &[ParamType::Float], 1)?
            .map(|v| v.to_vec()))
    }

    /// All values of `"integer name" [...]`, or `None` when absent.
    pub fn get_ints(&mut self, name: &str) -> Result<Option<Vec<i32>>, SceneError> {
        let Some(p) = self.typed(name, &[ParamType::Integer])? else {
            return Ok(None);
        };
        match &p.values {
            ParamValues::Ints(v) => Ok(Some(v.clone())),
            _ => Err(p.err("expected integers")),
        }
    }

    /// Numbers grouped in threes, for one of `types`.
    fn triples(
        &mut self,
        name: &str,
        types: &[ParamType],
    ) -> Result<Option<Vec<Vec3>>, SceneError> {
        Ok(self.numbers(name, types, 3)?.map(|v| {
            v.chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect()
        }))
    }

    /// All colours of `"rgb name" [...]`, or `None` when absent.
    pub fn get_rgbs(&mut self, name: &str) -> Result<Option<Vec<Vec3>>, SceneError> {
        self.triples(name, &[ParamType::Rgb])
    }

    /// All points of `"point3 name" [...]`, or `None` when absent.
    pub fn get_point3s(&mut self, name: &str) -> Result<Option<Vec<Vec3>>, SceneError> {
        self.triples(name, &[ParamType::Point3])
    }

    /// All normals of `"normal name" [...]`, or `None` when absent.
    pub fn get_normals(&mut self, name: &str) -> Result<Option<Vec<Vec3>>, SceneError> {
        self.triples(name, &[ParamType::Normal])
    }

    /// All points of `"point2 name" [...]`, or `None` when absent.
    pub fn get_point2s(&mut self, name: &str) -> Result<Option<Vec<Vec2>>, SceneError> {
        Ok(self
            .numbers(name, &[ParamType::Point2], 2)?
            .map(|v| v.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;
    use std::sync::Arc;

    fn loc(line: u32) -> Loc {
        Loc {
            file: Arc::new(PathBuf::from("p.pbrt")),
            line,
            col: 1,
        }
    }

    fn set() -> ParamSet {
        let mut s = ParamSet::new();
        let f = ParamValues::Floats;
        s.push(Param::new(
            ParamType::Float,
            "float",
            "fov",
            f(vec![30.0]),
            loc(1),
        ))
        .unwrap();
        s.push(Param::new(
            ParamType::Rgb,
            "color",
            "L",
            f(vec![1.0, 2.0, 3.0]),
            loc(2),
        ))
        .unwrap();
        s.push(Param::new(
            ParamType::Integer,
            "integer",
            "n",
            ParamValues::Ints(vec![1, 2]),
            loc(3),
        ))
        .unwrap();
        s
    }

    #[test]
    fn getters_read_and_mark() {
        let mut s = set();
        assert_eq!(s.get_float("fov", 90.0).unwrap(), 30.0);
        assert_eq!(s.get_float("absent", 7.0).unwrap(), 7.0);
        assert_eq!(
            s.get_rgb("L", Vec3::ZERO).unwrap(),
            Vec3::new(1.0, 2.0, 3.0)
        );
        let e = s.check_unused().unwrap_err();
        assert_eq!(e.loc.unwrap().line, 3);
        assert_eq!(e.msg, "unused parameter \"integer n\"");
        assert_eq!(s.get_ints("n").unwrap(), Some(vec![1, 2]));
        s.check_unused().unwrap();
    }

    #[test]
    fn type_and_arity_errors_name_the_parameter() {
        let mut s = set();
        let e = s.get_rgb("fov", Vec3::ZERO).unwrap_err();
        assert_eq!(e.loc.as_ref().unwrap().line, 1);
        assert!(
            e.msg.contains("\"float fov\"") && e.msg.contains("expected rgb"),
            "{}",
            e.msg
        );
        let e = s.get_int("n", 0).unwrap_err();
        assert!(e.msg.contains("expected 1 value, got 2"), "{}", e.msg);
        let dup = Param::new(
            ParamType::Float,
            "float",
            "fov",
            ParamValues::Floats(vec![1.0]),
            loc(9),
        );
        assert_eq!(s.push(dup).unwrap_err().loc.unwrap().line, 9);
    }
}
