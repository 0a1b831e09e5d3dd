//! wgpu renderer for voxel worlds with selectable order-independent transparency.
//!
//! - [`GpuContext`]: the game's device and queue, or a headless one.
//! - [`Renderer`]: chunks on the GPU and the passes of a frame; [`Camera`] to look with.
//! - [`oit`]: the transparency techniques behind [`OitManager`], one folder each.
//! - [`Image`] and [`readback`]: pictures back to the CPU, PNG files.
//!
//! Modules depend on each other one way, from the bottom: `error`, `context`, `camera`,
//! `readback`, `timing` → `gpu` (pass and pipeline plumbing) → `bindings` (what every chunk
//! pipeline binds), `textures` → `chunks` → `oit` (techniques) → `renderer`. A test checks
//! that no `crate::` path points back up.

mod bindings;
mod camera;
mod chunks;
mod context;
mod error;
pub mod gpu;
pub mod oit;
pub mod readback;
mod renderer;
pub mod textures;
mod timing;
#[cfg(test)]
mod wgsl_layout;

pub use bindings::{ChunkUniforms, FrameUniforms, SharedLayouts};
pub use camera::{Camera, MAX_FAR, MAX_FOV_DEG, MIN_FOV_DEG, MIN_NEAR, WORLD_EXTENT};
pub use chunks::{ChunkStore, Frustum, GpuChunk, GpuMesh, MeshKind, Visible};
pub use context::{Capabilities, GpuContext, WANTED_FEATURES, request_device};
pub use error::{Error, Result};
pub use oit::{
    BayerSize, OitConfig, OitManager, PeelReport, PeelingSettings, ReferenceReport, ShadingState,
    SortReport, SortedSettings, StippleSettings, Technique, TechniqueReport, TranslucentFrame,
    TranslucentTechnique, WboitReport, WboitSettings, WeightFit, WeightFunction,
};
pub use readback::Image;
pub use renderer::{FrameStats, Renderer, RendererConfig};
pub use timing::{GpuPass, GpuTimes, Timer};

/// Depth format of every pass: 32-bit float, reverse-Z (1 near, 0 far).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The HDR scene colour format (seed 003): opaque image, composites, before tonemapping.
pub const SCENE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

#[cfg(test)]
mod tests {
    /// The order of the module docs: a module may only `use crate::` modules listed before
    /// it (or itself). Checked on the source text, so a new back-edge fails here.
    const LAYERS: &[&str] = &[
        "error", "context", "camera", "readback", "timing", "gpu", "bindings", "textures",
        "chunks", "oit", "renderer",
    ];

    fn rank(module: &str) -> usize {
        LAYERS
            .iter()
            .position(|m| *m == module)
            .unwrap_or_else(|| panic!("module {module} is not in LAYERS"))
    }

    /// The module each item re-exported by lib.rs (`pub use module::{A, B};`) comes from.
    fn reexports(lib: &str) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for stmt in lib.split("pub use ").skip(1) {
            let stmt = &stmt[..stmt.find(';').unwrap_or(stmt.len())];
            let Some((module, items)) = stmt.split_once("::") else {
                continue;
            };
            for item in items.split(|c: char| "{}, \n".contains(c)) {
                let item = item.rsplit("::").next().unwrap_or("").trim();
                if !item.is_empty() {
                    out.push((item.to_owned(), module.trim().to_owned()));
                }
            }
        }
        out
    }

    /// The modules `source` reaches through `crate::module` paths, or through items
    /// lib.rs re-exports (`crate::Renderer` is `renderer`).
    fn uses(source: &str, reexported: &[(String, String)]) -> Vec<String> {
        let mut out = Vec::new();
        let mut add = |m: String| {
            if !out.contains(&m) {
                out.push(m);
            }
        };
        for (i, _) in source.match_indices("crate::") {
            let rest = &source[i + 7..];
            let mut names = vec![];
            if let Some(group) = rest.strip_prefix('{') {
                names.extend(
                    group[..group.find('}').unwrap_or(0)]
                        .split(',')
                        .map(str::trim),
                );
            } else {
                names.push(rest);
            }
            for n in names {
                let name: String = n
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if name.chars().next().is_some_and(|c| c.is_ascii_lowercase()) {
                    add(name);
                } else if let Some((_, m)) = reexported.iter().find(|(item, _)| *item == name) {
                    add(m.clone());
                }
            }
        }
        out
    }

    fn sources(dir: &std::path::Path, out: &mut Vec<(std::path::PathBuf, String)>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                sources(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push((p.clone(), std::fs::read_to_string(&p).unwrap()));
            }
        }
    }

    #[test]
    fn module_dependencies_point_one_way() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let reexported = reexports(&std::fs::read_to_string(src.join("lib.rs")).unwrap());
        assert!(
            reexported
                .iter()
                .any(|(i, m)| i == "Renderer" && m == "renderer")
        );
        let mut files = Vec::new();
        sources(&src, &mut files);
        for (path, text) in files {
            let rel = path.strip_prefix(&src).unwrap();
            let top = rel
                .components()
                .next()
                .unwrap()
                .as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_owned();
            if top == "lib" || top == "wgsl_layout" {
                continue;
            }
            // Test code may reach anywhere.
            let text = text.split("#[cfg(test)]").next().unwrap_or("");
            for used in uses(text, &reexported) {
                if used == "wgsl_layout" {
                    continue;
                }
                assert!(
                    rank(&used) <= rank(&top),
                    "{} uses crate::{used}, which sits above {top}",
                    rel.display()
                );
            }
        }
    }
}
