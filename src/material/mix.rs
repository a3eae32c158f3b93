//! `mix`: at each hit one of two named materials defined earlier, the second with
//! probability `amount` (pbrt-v4's stochastic `MixMaterial`: a hash of the point and `wo`
//! against `amount`; see [`crate::interaction::SurfaceInteraction::bsdf`]).
//!
//! ```text
//! MakeNamedMaterial "wood" "string type" "diffuse" ...
//! Material "mix" "string materials" [ "wood" "paint" ] "texture amount" "wear"   # amount 0.5
//! ```
//! Mixes may nest at most [`super::MAX_MIX_DEPTH`] deep; `displacement` is not read (pbrt-v4's
//! mix has none).
use super::parts::tex;
use super::{Material, MaterialContext, MaterialKind, MaterialModel, MAX_MIX_DEPTH};
use crate::bsdf::{Bsdf, BxdfFlags, Diffuse};
use crate::params::{Loc, ParamSet, SceneError};
use crate::spectrum::Spectrum;
use crate::texture::{Tex, TexCoord};
use std::collections::HashMap;

#[derive(Clone, Debug, PartialEq)]
pub struct MixMaterial {
    /// Indices into the scene's materials.
    pub materials: [u32; 2],
    /// The probability of the second material.
    pub amount: Tex,
    /// The union of the two materials' flags.
    pub flags: BxdfFlags,
}

impl MaterialModel for MixMaterial {
    /// `"string materials" [ "a" "b" ]` (named materials defined earlier) and `amount` (float
    /// or float texture, default 0.5).
    fn create(params: &mut ParamSet, loc: &Loc, cx: &MaterialContext) -> Result<Self, SceneError> {
        let Some(p) = params.get_param("materials") else {
            return Err(SceneError::at(
                loc,
                "mix needs \"string materials\" naming two materials",
            ));
        };
        let names: Vec<String> = match p.strings() {
            Some(v) if v.len() == 2 => v.to_vec(),
            _ => return Err(p.err("expected two material names")),
        };
        let mut materials = [0u32; 2];
        let mut flags = BxdfFlags::default();
        for (i, name) in names.iter().enumerate() {
            let Some(&idx) = cx.named.get(name) else {
                return Err(p.err(format!("unknown named material \"{name}\"")));
            };
            materials[i] = idx;
            flags = flags | cx.materials[idx as usize].kind.flags();
        }
        let depth = 1 + materials
            .iter()
            .map(|&m| mix_depth(cx.materials, m, &mut HashMap::new()))
            .max()
            .unwrap_or(0);
        if depth > MAX_MIX_DEPTH {
            return Err(p.err(format!(
                "this mix nests {depth} mix materials (at most {})",
                MAX_MIX_DEPTH
            )));
        }
        let amount = tex(params, "amount", false, 0.5, cx.textures)?;
        Ok(MixMaterial {
            materials,
            amount,
            flags,
        })
    }

    fn flags(&self) -> BxdfFlags {
        self.flags
    }

    /// A mix is resolved to one of its materials before a BSDF is made; one that reaches here
    /// reflects nothing.
    fn bsdf(&self, _: &TexCoord) -> Bsdf {
        Bsdf::Diffuse(Diffuse::new(Spectrum::ZERO))
    }

    fn for_each_texture(&self, f: &mut dyn FnMut(&Tex)) {
        f(&self.amount)
    }
}

/// How many `mix` materials deep material `m` nests (0 for any other material); `memo` keeps
/// each material's depth so that a mix naming the same mix twice at every level costs linear
/// time. Mixes name materials defined before them, so the recursion ends (and was checked to
/// be at most [`crate::scene::MAX_MIX_DEPTH`] deep when each was made).
fn mix_depth(materials: &[Material], m: u32, memo: &mut HashMap<u32, usize>) -> usize {
    if let Some(&d) = memo.get(&m) {
        return d;
    }
    let d = match &materials[m as usize].kind {
        MaterialKind::Mix(MixMaterial { materials: two, .. }) => {
            1 + two
                .iter()
                .map(|&c| mix_depth(materials, c, memo))
                .max()
                .unwrap_or(0)
        }
        _ => 0,
    };
    memo.insert(m, d);
    d
}
