//! STUB: being written.
use super::{AccelError, AccelOptions, Hit, RayQuery};
use crate::math::Ray;
use crate::scene::Scene;

pub struct BvhAccel;

impl BvhAccel {
    pub fn build(_scene: &Scene, _opts: AccelOptions) -> Result<Self, AccelError> {
        Err(AccelError("not yet implemented".into()))
    }
}

impl RayQuery for BvhAccel {
    fn intersect(&self, _ray: &Ray) -> Option<Hit> {
        None
    }
    fn occluded(&self, _ray: &Ray) -> bool {
        false
    }
}
