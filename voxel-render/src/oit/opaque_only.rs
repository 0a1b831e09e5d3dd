//! Translucent meshes not drawn at all: the opaque picture, for comparison (what every
//! technique's error is relative to when nothing translucent is in view).

use crate::context::Capabilities;
use crate::oit::{
    OitConfig, Setup, Technique, TechniqueKind, TranslucentFrame, TranslucentTechnique,
};
use crate::{GpuContext, Result};

/// Draws nothing; never created (it does not draw, so the manager skips it).
#[derive(Debug)]
pub(crate) struct OpaqueOnly;

impl TechniqueKind for OpaqueOnly {
    type Key = ();
    const DRAWS: bool = false;

    fn key(_: Technique, _: &OitConfig, _: &Capabilities) {}

    fn create(_: &Setup, _: Technique, _: &OitConfig) -> Result<Self> {
        Ok(Self)
    }
}

impl TranslucentTechnique for OpaqueOnly {
    fn resize(&mut self, _: &GpuContext, _: u32, _: u32) -> Result<()> {
        Ok(())
    }

    fn render(
        &mut self,
        _: &GpuContext,
        _: &mut wgpu::CommandEncoder,
        _: &TranslucentFrame<'_>,
    ) -> Result<()> {
        Ok(())
    }

    /// No pass: a game's translucent geometry is not drawn either.
    fn variants(&self) -> Vec<crate::stages::TranslucentVariant> {
        Vec::new()
    }
}
