//! A volume's way out at a T-junction of its surface (`scenes/regressions/
//! sky_from_sunken_bell.toml`): from inside a glass bell sunk in water, one pixel's ray
//! leaves the water through the surface within 1/1000 px of the seam where two merged quads
//! meet, a point the rasteriser covers with neither. The passes that only say where a
//! volume ends (the volume exit of the real-time techniques, and the exact references'
//! exit pass that ends a medium still open after their last fragment) draw the quads grown,
//! as the opaque pass does against cracks, so the path through the water ends at the
//! surface there too: before, the sky seen through the water came out as the water's own
//! colour (27/255 darker) in every technique and reference. On lavapipe, as CI runs it: the
//! sliver depends on the rasteriser.

#![allow(clippy::unwrap_used)] // test code: a failed unwrap is a failed test

use tests::{gpu, render_with, technique_config};
use voxel_lab::scene::Scene;
use voxel_render::{Image, Technique};

fn rgb(img: &Image, x: u32, y: u32) -> [u8; 3] {
    let p = img.pixel(x, y);
    [p[0], p[1], p[2]]
}

#[test]
fn the_water_surface_ends_the_path_at_a_t_junction_seen_from_inside_a_sunken_bell() {
    let Some(ctx) = gpu() else { return };
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/regressions/sky_from_sunken_bell.toml"
    );
    let scene = Scene::load(std::path::Path::new(path)).unwrap();
    let (w, h) = (640, 360);
    // The exact references agree with the ray march there (and everywhere off edges).
    let check = voxel_lab::eval::raymarch_check(&ctx, &scene, &scene.cameras[0], (w, h)).unwrap();
    let c = &check.comparison;
    assert_eq!(
        (c.differing, c.cracks),
        (0, 0),
        "the A-buffer against the ray march: {:?}",
        c.worst
    );
    // Every real-time technique draws the pixel like its neighbours, which see the sky
    // through the water too (within the few 1/255 a pixel's ray length changes).
    for technique in [
        Technique::SortedQuads,
        Technique::Sorted,
        Technique::DepthPeeling,
        Technique::WboitMrt,
    ] {
        let mut config = technique_config(technique, w, h);
        config.flat_textures = true;
        let img = render_with(&ctx, &scene, config);
        let (left, at, right) = (
            rgb(&img, 350, 242),
            rgb(&img, 351, 242),
            rgb(&img, 352, 242),
        );
        assert!(
            (0..3).all(|k| at[k] + 4 >= left[k].min(right[k])),
            "{}: {left:?} {at:?} {right:?}",
            technique.name()
        );
    }
}
