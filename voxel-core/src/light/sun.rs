//! Sun shadows: how much of the sun's direct light reaches a point, per channel, after the
//! blocks along the ray toward the sun (a voxel march). The same filters as the light field's
//! sky beam ([`super::props`]): air lets all through, a translucent block one block of its
//! volume, times its surface where the ray enters it from a cell of another type; opaque and
//! cutout blocks stop it (leaves cast shade, as they stop the beam). The renderer marches the
//! same cells in its shaders (`voxel-render`'s sun shadows); this is the CPU twin that a
//! game's content and the lab's reference read.

use super::props;
use crate::{BlockId, BlockRegistry, CHUNK_SIZE, RenderClass, World, WorldPos};

/// How the sun's ray crosses a block type that lets it through ([`SunFilters::get`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunCell {
    /// The type whose surfaces the ray crosses: 0 for air, the block's own id for a
    /// translucent block. Between two cells of the same kind the ray crosses no surface.
    pub kind: u16,
    /// Filter per channel of a cell the ray enters from a cell of another kind: the
    /// surface, then one block of the volume.
    pub enter: [f32; 3],
    /// Filter per channel of a cell the ray enters from a cell of its own kind.
    pub within: [f32; 3],
}

impl SunCell {
    /// Air's: everything through.
    pub const AIR: SunCell = SunCell {
        kind: 0,
        enter: [1.0; 3],
        within: [1.0; 3],
    };

    /// This cell's filter for a ray that reaches it from a cell of kind `from`.
    pub fn filter(&self, from: u16) -> [f32; 3] {
        if from == self.kind {
            self.within
        } else {
            self.enter
        }
    }
}

/// Per block id of a registry, how the sun's ray crosses it: `None` for a block that stops
/// it (opaque and cutout blocks).
#[derive(Clone, Debug, PartialEq)]
pub struct SunFilters {
    cells: Vec<Option<SunCell>>,
}

impl SunFilters {
    /// The filters of every block of `registry`, the light field's.
    pub fn new(registry: &BlockRegistry) -> Self {
        let cells = props::table(registry)
            .iter()
            .zip(registry.iter())
            .map(|(p, (_, def))| match def.class {
                RenderClass::Air => Some(SunCell::AIR),
                RenderClass::Translucent => Some(SunCell {
                    kind: p.kind,
                    enter: p.enter,
                    within: p.within,
                }),
                RenderClass::Opaque | RenderClass::Cutout => None,
            })
            .collect();
        Self { cells }
    }

    /// How the ray crosses block `id`; `None` where it stops (an id outside the registry
    /// too: a world over this registry holds none).
    pub fn get(&self, id: BlockId) -> Option<SunCell> {
        self.cells.get(usize::from(id.0)).copied().flatten()
    }

    /// Every block id's, by id.
    pub fn cells(&self) -> &[Option<SunCell>] {
        &self.cells
    }

    /// The share of the sun's direct light, per channel (0 to 1), that reaches point `from`
    /// from direction `dir` (toward the sun, any length) through the blocks `block` gives
    /// inside `bounds` (blocks from the first corner, included, to the second, excluded;
    /// air outside): the product of the filters of the cells the ray crosses from `from`'s
    /// cell (included) to where it leaves the bounds. 0 when a cell on the way stops the
    /// sun, and for a sun at or below the horizon (`dir.y <= 0`, or not finite): the ground
    /// hides it. `from` should lie inside the cell the light is wanted for (a point on a
    /// face, moved a little along the face's normal).
    pub fn march(
        &self,
        bounds: ([i64; 3], [i64; 3]),
        block: impl Fn([i64; 3]) -> BlockId,
        from: [f64; 3],
        dir: [f64; 3],
    ) -> [f32; 3] {
        if !(dir[1] > 0.0 && dir.iter().chain(&from).all(|v| v.is_finite())) {
            return [0.0; 3];
        }
        let outside = |c: [i64; 3]| (0..3).any(|a| c[a] < bounds.0[a] || c[a] >= bounds.1[a]);
        let cell_at = |c: [i64; 3]| {
            if outside(c) {
                Some(SunCell::AIR)
            } else {
                self.get(block(c))
            }
        };
        let mut cell = from.map(|v| v.floor() as i64);
        let step = dir.map(|d| if d > 0.0 { 1 } else { -1 });
        let delta = dir.map(|d| {
            if d == 0.0 {
                f64::INFINITY
            } else {
                1.0 / d.abs()
            }
        });
        let mut next: [f64; 3] = std::array::from_fn(|a| {
            let d = dir[a];
            if d > 0.0 {
                (cell[a] as f64 + 1.0 - from[a]) / d
            } else if d < 0.0 {
                (cell[a] as f64 - from[a]) / d
            } else {
                f64::INFINITY
            }
        });
        let Some(mut prev) = cell_at(cell) else {
            return [0.0; 3];
        };
        let mut t = [1.0f32; 3];
        loop {
            let a = axis_of_min(next);
            cell[a] += step[a];
            next[a] += delta[a];
            let Some(here) = cell_at(cell) else {
                return [0.0; 3];
            };
            // The light enters the previous cell from this one.
            let f = prev.filter(here.kind);
            t = std::array::from_fn(|c| t[c] * f[c]);
            if outside(cell) {
                return t;
            }
            prev = here;
        }
    }
}

/// Marches rays toward the sun through a world's loaded chunks.
#[derive(Clone, Debug)]
pub struct SunMarch<'w> {
    world: &'w World,
    filters: SunFilters,
    /// Blocks `min..=max` hold every loaded chunk; outside them all is air.
    min: [i64; 3],
    max: [i64; 3],
}

impl<'w> SunMarch<'w> {
    /// A march over `world` as it is now (its loaded chunks bound the walk).
    pub fn new(world: &'w World) -> Self {
        let (min, max) = match world.chunk_bounds() {
            Some((lo, hi)) => (lo.origin(), hi.origin().map(|o| o + CHUNK_SIZE as i64 - 1)),
            None => ([i64::MAX; 3], [i64::MIN; 3]),
        };
        Self {
            world,
            filters: SunFilters::new(world.registry()),
            min,
            max,
        }
    }

    /// The filters it uses.
    pub fn filters(&self) -> &SunFilters {
        &self.filters
    }

    /// The share of the sun's direct light, per channel (0 to 1), that reaches point `from`
    /// from direction `dir` (toward the sun, any length): [`SunFilters::march`] over the
    /// world's loaded chunks.
    pub fn transmittance(&self, from: [f64; 3], dir: [f64; 3]) -> [f32; 3] {
        let bounds = (self.min, self.max.map(|m| m.saturating_add(1)));
        self.filters.march(
            bounds,
            |c| {
                self.world
                    .get_block(WorldPos::new(c[0] as i32, c[1] as i32, c[2] as i32))
            },
            from,
            dir,
        )
    }
}
/// The axis of the smallest of `t` (the first on ties: x, then y, then z), the order the
/// renderer's march steps in too.
fn axis_of_min(t: [f64; 3]) -> usize {
    if t[0] <= t[1] && t[0] <= t[2] {
        0
    } else if t[1] <= t[2] {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::blocks;

    fn world() -> World {
        let mut w = World::new(Arc::new(BlockRegistry::default()));
        w.fill_box(
            WorldPos::new(0, 0, 0),
            WorldPos::new(31, 0, 31),
            blocks::STONE,
        )
        .unwrap();
        w
    }

    #[test]
    fn open_sky_lets_everything_through() {
        let w = world();
        let m = SunMarch::new(&w);
        assert_eq!(
            m.transmittance([5.5, 1.001, 5.5], [0.3, 0.8, 0.2]),
            [1.0; 3]
        );
    }

    #[test]
    fn a_wall_toward_the_sun_casts_shade_and_one_beside_it_does_not() {
        let mut w = world();
        // A wall at x = 10, y 1..=6: the sun in +x at 45 degrees.
        w.fill_box(
            WorldPos::new(10, 1, 0),
            WorldPos::new(10, 6, 31),
            blocks::STONE,
        )
        .unwrap();
        let m = SunMarch::new(&w);
        let sun = [1.0, 1.0, 0.0];
        assert_eq!(m.transmittance([7.5, 1.001, 5.5], sun), [0.0; 3]);
        // Past the wall's height along the ray: lit.
        assert_eq!(m.transmittance([2.5, 1.001, 5.5], sun), [1.0; 3]);
        // The sun behind: lit.
        assert_eq!(
            m.transmittance([7.5, 1.001, 5.5], [-1.0, 1.0, 0.0]),
            [1.0; 3]
        );
        // Below the horizon or NaN: dark.
        assert_eq!(
            m.transmittance([7.5, 1.001, 5.5], [1.0, 0.0, 0.0]),
            [0.0; 3]
        );
        assert_eq!(m.transmittance([f64::NAN, 1.001, 5.5], sun), [0.0; 3]);
    }

    #[test]
    fn a_pane_tints_and_water_darkens_with_depth() {
        let r = BlockRegistry::default();
        let f = SunFilters::new(&r);
        let red = f.get(blocks::RED_GLASS).unwrap();
        let water = f.get(blocks::WATER).unwrap();
        let mut w = world();
        // A red pane at y = 5 over x 0..8.
        w.fill_box(
            WorldPos::new(0, 5, 0),
            WorldPos::new(8, 5, 31),
            blocks::RED_GLASS,
        )
        .unwrap();
        // Water 4 deep over x 20..31, y 1..=4.
        w.fill_box(
            WorldPos::new(20, 1, 0),
            WorldPos::new(31, 4, 31),
            blocks::WATER,
        )
        .unwrap();
        let m = SunMarch::new(&w);
        let up = [0.0, 1.0, 0.0];
        let t = m.transmittance([3.5, 1.001, 3.5], up);
        for c in 0..3 {
            assert!((t[c] - red.enter[c]).abs() < 1e-6, "{t:?}");
        }
        // The floor under the water: four blocks of water, one surface.
        let t = m.transmittance([25.5, 1.001, 3.5], up);
        for c in 0..3 {
            let want = water.enter[c] * water.within[c].powi(3);
            assert!((t[c] - want).abs() < 1e-6, "{t:?} {want}");
        }
        // Slanting through the water crosses more of its cells: darker.
        let s = m.transmittance([25.5, 1.001, 3.5], [0.0, 1.0, 1.0]);
        assert!(s[2] < t[2], "{s:?} {t:?}");
        // The sun's ray shifted off the pane: unfiltered.
        assert_eq!(
            m.transmittance([3.5, 1.001, 3.5], [1.0, 0.5, 0.0]),
            [1.0; 3]
        );
    }
}
