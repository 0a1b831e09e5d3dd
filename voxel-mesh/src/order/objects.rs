//! A set of quads split into objects: classes of touching quads, merged until any two
//! classes' bounding boxes are separated along some axis.

use super::relation::QBox;

/// A bounding box: minimum and maximum corners.
pub(super) type Bounds = ([i32; 3], [i32; 3]);

/// Splits the quads `ids` into objects: the classes of quads whose closed boxes chain
/// together by touching or overlapping, merged while the bounding boxes of two classes are
/// not separated along any axis (so that any two objects' boxes are). Each with its
/// bounding box, in order of smallest member.
pub(super) fn objects(all: &[QBox], ids: &[u32]) -> Vec<(Vec<u32>, Bounds)> {
    let n = ids.len();
    let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
    for &i in ids {
        let b = &all[i as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(b.lo[k]);
            hi[k] = hi[k].max(b.hi[k]);
        }
    }
    let dim = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as usize);
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    fn union(p: &mut [u32], a: u32, b: u32) {
        let (a, b) = (find(p, a), find(p, b));
        p[a.max(b) as usize] = a.min(b);
    }
    // Closed integer boxes that meet share a lattice point: union through a lattice grid.
    let mut grid = vec![u32::MAX; dim[0] * dim[1] * dim[2]];
    for (j, &i) in ids.iter().enumerate() {
        let b = &all[i as usize];
        for x in b.lo[0]..=b.hi[0] {
            for y in b.lo[1]..=b.hi[1] {
                for z in b.lo[2]..=b.hi[2] {
                    let at = (((x - lo[0]) as usize * dim[1]) + (y - lo[1]) as usize) * dim[2]
                        + (z - lo[2]) as usize;
                    match grid[at] {
                        u32::MAX => grid[at] = j as u32,
                        o => union(&mut parent, j as u32, o),
                    }
                }
            }
        }
    }
    let bounds = |members: &[u32]| {
        let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
        for &j in members {
            let b = &all[ids[j as usize] as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(b.lo[k]);
                hi[k] = hi[k].max(b.hi[k]);
            }
        }
        (lo, hi)
    };
    let not_separated = |a: &Bounds, b: &Bounds| (0..3).all(|k| a.0[k] < b.1[k] && b.0[k] < a.1[k]);
    loop {
        let mut classes: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
        for j in 0..n as u32 {
            classes.entry(find(&mut parent, j)).or_default().push(j);
        }
        let classes: Vec<(u32, Bounds)> = classes
            .into_iter()
            .map(|(root, members)| (root, bounds(&members)))
            .collect();
        let mut merged = false;
        for a in 0..classes.len() {
            for b in a + 1..classes.len() {
                if not_separated(&classes[a].1, &classes[b].1) {
                    union(&mut parent, classes[a].0, classes[b].0);
                    merged = true;
                }
            }
        }
        if !merged {
            break;
        }
    }
    let mut classes: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for j in 0..n as u32 {
        classes
            .entry(find(&mut parent, j))
            .or_default()
            .push(ids[j as usize]);
    }
    classes
        .into_values()
        .map(|members| {
            let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
            for &i in &members {
                let b = &all[i as usize];
                for k in 0..3 {
                    lo[k] = lo[k].min(b.lo[k]);
                    hi[k] = hi[k].max(b.hi[k]);
                }
            }
            (members, (lo, hi))
        })
        .collect()
}
