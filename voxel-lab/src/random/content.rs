//! A game's content in a random scene: particles and entities around the target, drawn
//! from their own stream of the seed and index.

use super::boxes::{add, length, off_grid, sub};
use super::{Features, SplitMix64, num, vec3};

/// A game's particles and entities around the target, from their own stream (so the
/// blocks and the camera of a scene do not depend on them): `[[particles]]` and
/// `[[entities]]` text in local coordinates moved by `off`, and the counts in `f`.
pub(super) fn content(
    seed: u64,
    index: usize,
    eye: [f64; 3],
    target: [f64; 3],
    near: f64,
    off: [f64; 3],
    f: &mut Features,
) -> String {
    let mut rng = SplitMix64::new(
        seed ^ (index as u64).wrapping_mul(0x94D0_49BB_1331_11EB) ^ 0x5EED_C0DE_0000_0001,
    );
    rng.next_u64();
    let mut t = String::new();
    let distance = length(sub(target, eye));
    let color = |rng: &mut SplitMix64| {
        let c = [0; 3].map(|_| rng.int(0, 255));
        format!("[{}, {}, {}]", c[0], c[1], c[2])
    };
    if rng.chance(0.35) {
        // A cloud around the target, never reaching the eye.
        let r = (distance * 0.3).clamp(0.5, 12.0);
        let half = [0; 3].map(|_| off_grid(rng.range(0.4, 1.0) * r));
        let count = if rng.chance(0.6) {
            rng.int(100, 1000)
        } else {
            rng.int(1000, 5000)
        };
        t += &format!(
            "\n[[particles]]\nmin = {}\nmax = {}\ncount = {count}\nseed = {}\nsize = {}\ncolor = {}\nopacity = {}\n",
            vec3(add(sub(target, half), off)),
            vec3(add(add(target, half), off)),
            rng.int(1, 1_000_000),
            num(f64::from(rng.int(4, 40)) / 100.0),
            color(&mut rng),
            num(f64::from(rng.int(10, 90)) / 100.0),
        );
        f.particles = count as u32;
    }
    if rng.chance(0.3) {
        let spread = (distance * 0.3).clamp(0.5, 6.0);
        for _ in 0..rng.int(1, 3) {
            let size = [0; 3].map(|_| f64::from(rng.int(5, 40)) / 10.0);
            let center = [0, 1, 2].map(|k| off_grid(target[k] + rng.range(-spread, spread)));
            let rotation = [rng.int(0, 359), rng.int(-89, 89), rng.int(-89, 89)];
            let opaque = rng.chance(0.3);
            let opacity = if opaque {
                1.0
            } else {
                f64::from(rng.int(10, 95)) / 100.0
            };
            let c = color(&mut rng);
            // Not around the eye: its back faces are culled, so it would vanish.
            let reach = length(size) / 2.0;
            if length(sub(center, eye)) < reach + near + 0.1 {
                continue;
            }
            t += &format!(
                "\n[[entities]]\ncenter = {}\nsize = {}\nrotation = [{}.0, {}.0, {}.0]\ncolor = {c}\nopacity = {}\n",
                vec3(add(center, off)),
                vec3(size),
                rotation[0],
                rotation[1],
                rotation[2],
                num(opacity),
            );
            if opaque {
                f.opaque_entities += 1;
            } else {
                f.translucent_entities += 1;
            }
        }
    }
    t
}
