use super::leaf::{Leaf, clear_bits};
use super::objects::objects;
use super::relation::{QBox, SInterval, Span, hides_at, may_hide_in_cell, tie_at};
use super::*;
use crate::Mesher;
use crate::PackedQuad;
use voxel_core::blocks::{AIR, GLASS, RED_GLASS, WATER};
use voxel_core::{BlockRegistry, Chunk, Face};

/// xorshift64*.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    /// A dyadic coordinate in `lo..hi`.
    fn coord(&mut self, lo: f64, hi: f64) -> f64 {
        lo + ((hi - lo) * 1024.0 * (self.below(1 << 20) as f64 / (1 << 20) as f64)).floor() / 1024.0
    }
}

fn random_quads(rng: &mut Rng) -> Vec<PackedQuad> {
    let mut c = Chunk::uniform(AIR);
    for _ in 0..1 + rng.below(8) {
        let id = [GLASS, RED_GLASS, WATER, AIR][rng.below(4) as usize];
        let lo = [0; 3].map(|_| 4 + rng.below(12) as usize);
        let hi = lo.map(|v| v + rng.below(5) as usize);
        c.fill_box(lo, hi, id).unwrap_or_default();
    }
    let reg = BlockRegistry::default();
    Mesher::new(&reg)
        .mesh(&c, [None; 6])
        .map(|m| m.translucent)
        .unwrap_or_default()
}

/// A random open cell with integer bounds (possibly unbounded), and an eye inside it.
fn random_cell(rng: &mut Rng) -> ([Span; 3], [f64; 3]) {
    let mut cell = [Span { lo: None, hi: None }; 3];
    let mut eye = [0.0; 3];
    for k in 0..3 {
        let a = 2 + rng.below(20) as i32;
        let b = a + 1 + rng.below(4) as i32;
        cell[k] = match rng.below(4) {
            0 => Span {
                lo: None,
                hi: Some(b),
            },
            1 => Span {
                lo: Some(a),
                hi: None,
            },
            _ => Span {
                lo: Some(a),
                hi: Some(b),
            },
        };
        let lo = cell[k].lo.map_or(f64::from(b) - 40.0, f64::from);
        let hi = cell[k].hi.map_or(f64::from(a) + 40.0, f64::from);
        eye[k] = rng.coord(lo, hi).max(lo + 1.0 / 1024.0);
    }
    (cell, eye)
}

/// The relation at a point, with the tie-breaks of planes that the cell does not
/// straddle (the structure makes every tie plane a trigger plane, so its cells never
/// straddle one; these tests draw cells at random).
fn before_at(eye: [f64; 3], a: &QBox, b: &QBox, cell: &[Span; 3]) -> bool {
    let c = cell[a.axis];
    let straddled = !c.above(a.plane()) && !c.below(a.plane());
    hides_at(eye, a, b) || (tie_at(eye, a, b) && !straddled)
}

#[test]
fn the_region_relation_contains_the_relation_at_every_eye_of_the_cell() {
    let mut rng = Rng(7);
    let mut related = 0;
    for _ in 0..200 {
        let quads: Vec<QBox> = random_quads(&mut rng).into_iter().map(QBox::of).collect();
        for _ in 0..4 {
            let (cell, _) = random_cell(&mut rng);
            for _ in 0..4 {
                let (_, eye) = {
                    // Another eye of the same cell.
                    let mut e = [0.0; 3];
                    for k in 0..3 {
                        let lo = cell[k].lo.map_or(-60.0, f64::from);
                        let hi = cell[k].hi.map_or(90.0, f64::from);
                        e[k] = (rng.coord(lo, hi)).max(lo + 1.0 / 1024.0);
                    }
                    ((), e)
                };
                for a in &quads {
                    for b in &quads {
                        if before_at(eye, a, b, &cell) {
                            related += 1;
                            assert!(
                                may_hide_in_cell(a, b, &cell),
                                "{a:?} {b:?} {cell:?} {eye:?}"
                            );
                        }
                    }
                }
            }
        }
    }
    assert!(related > 1000, "{related}");
}

#[test]
fn leaves_order_exactly_for_any_cell() {
    // Cells whose bounds need not be the leaf's coordinates (as for groups of objects):
    // the order must hold at every eye of the cell when exact for the region, and at the
    // eye itself otherwise.
    let mut rng = Rng(8);
    let (mut sorts, mut region_exact) = (0, 0);
    for _ in 0..300 {
        let mut boxes: Vec<QBox> = random_quads(&mut rng).into_iter().map(QBox::of).collect();
        if boxes.is_empty() {
            continue;
        }
        boxes.sort_by_key(|b| (b.axis, b.plane(), !b.positive, b.lo, b.hi));
        let leaf = Leaf::new(0, boxes.clone(), false, true);
        for _ in 0..6 {
            let (cell, eye) = random_cell(&mut rng);
            let mut order = Vec::new();
            let Some(stats) = leaf.order(&cell, Some(eye), &mut order) else {
                panic!("the eye was given");
            };
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..boxes.len() as u32).collect::<Vec<_>>());
            sorts += 1;
            let eyes: Vec<[f64; 3]> = if stats.is_exact_in_region() {
                region_exact += 1;
                (0..4)
                    .map(|_| {
                        let mut e = eye;
                        for k in 0..3 {
                            let lo = cell[k].lo.map_or(eye[k] - 50.0, f64::from);
                            let hi = cell[k].hi.map_or(eye[k] + 50.0, f64::from);
                            e[k] = rng.coord(lo, hi).max(lo + 1.0 / 1024.0);
                        }
                        e
                    })
                    .chain([eye])
                    .collect()
            } else if stats.is_exact() {
                vec![eye]
            } else {
                continue;
            };
            for e in eyes {
                for (i, &a) in order.iter().enumerate() {
                    for &b in &order[..i] {
                        // b is drawn before a: wrong if b must come after a.
                        assert!(
                            !before_at(e, &boxes[a as usize], &boxes[b as usize], &cell),
                            "cell {cell:?} eye {e:?}: {:?} before {:?}",
                            boxes[b as usize],
                            boxes[a as usize]
                        );
                    }
                }
            }
        }
    }
    assert!(
        sorts > 1000 && region_exact > sorts / 4,
        "{sorts} {region_exact}"
    );
}

#[test]
fn interval_of_s() {
    let mut s = SInterval::new();
    s.less(1, 3); // s < 3
    s.greater(2, 2); // s > 1
    assert!(s.feasible());
    s.less(3, 3); // s < 1
    assert!(!s.feasible());
    let mut s = SInterval::new();
    s.less(0, 0); // 0 < 0: never
    assert!(!s.feasible());
    let mut s = SInterval::new();
    s.less(-1, 5); // s > -5: no bound above 0
    assert!(s.feasible());
}

#[test]
fn region_keys_count_planes_strictly_below() {
    let glass = GLASS;
    let quads = [
        PackedQuad::new([1, 0, 0], 4, 4, Face::NegX, glass),
        PackedQuad::new([2, 0, 0], 4, 4, Face::NegX, glass),
        PackedQuad::new([3, 0, 0], 4, 4, Face::NegX, glass),
    ];
    let order = QuadOrder::new(&quads);
    assert_eq!(order.trigger_planes()[0], &[2]);
    let key = |x: f64| order.region_key([x, 0.5, 0.5]).0[0];
    assert_eq!(
        [
            key(-1.0e9),
            key(1.5),
            key(2.0),
            key(2.0 + 1e-12),
            key(1e300)
        ],
        [0, 0, 0, 1, 1]
    );
    assert_eq!(
        [key(f64::NAN), key(f64::INFINITY), key(f64::NEG_INFINITY)],
        [0, 1, 0]
    );
}

#[test]
fn bit_ranges_clear() {
    for (from, to) in [(0, 0), (0, 1), (3, 64), (63, 65), (10, 200), (64, 128)] {
        let mut row = [u64::MAX; 4];
        clear_bits(&mut row, from, to);
        for i in 0..256 {
            let set = row[i / 64] >> (i % 64) & 1 == 1;
            assert_eq!(set, !(from..to).contains(&i), "{from}..{to} at {i}");
        }
    }
}

#[test]
fn objects_are_classes_with_separated_boxes() {
    let mut rng = Rng(9);
    for _ in 0..100 {
        let all: Vec<QBox> = random_quads(&mut rng).into_iter().map(QBox::of).collect();
        let ids: Vec<u32> = (0..all.len() as u32).collect();
        if ids.is_empty() {
            continue;
        }
        let objs = objects(&all, &ids);
        let mut seen: Vec<u32> = objs.iter().flat_map(|o| o.0.clone()).collect();
        seen.sort_unstable();
        assert_eq!(seen, ids);
        for (i, a) in objs.iter().enumerate() {
            for b in &objs[i + 1..] {
                let separated = (0..3).any(|k| a.1.1[k] <= b.1.0[k] || b.1.1[k] <= a.1.0[k]);
                assert!(separated, "{a:?} {b:?}");
                // Quads of different objects never touch.
                for &p in &a.0 {
                    for &q in &b.0 {
                        let (p, q) = (&all[p as usize], &all[q as usize]);
                        assert!((0..3).any(|k| p.hi[k] < q.lo[k] || q.hi[k] < p.lo[k]));
                    }
                }
            }
        }
    }
}
