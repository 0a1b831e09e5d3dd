use super::bits::{side_index, transpose_layout_into, transpose32};
use super::packed::planes_for;
use super::*;
use crate::blocks::*;

/// A tiny xorshift, so the tests need no dependency and run the same every time.
fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

#[test]
fn set_and_get_round_trip() {
    let mut c = Chunk::default();
    assert_eq!(c.set(1, 2, 3, STONE).unwrap(), AIR);
    assert_eq!(c.get(1, 2, 3).unwrap(), STONE);
    assert_eq!(c.get(3, 2, 1).unwrap(), AIR);
    assert_eq!(c.set(1, 2, 3, WATER).unwrap(), STONE);
    assert_eq!(c.count(WATER), 1);
    assert_eq!(c.count(STONE), 0);
    assert_eq!(c.palette_len(), 2);
    c.check_invariants().unwrap();
}

#[test]
fn out_of_range_is_an_error() {
    let mut c = Chunk::default();
    assert_eq!(
        c.get(32, 0, 0),
        Err(Error::LocalOutOfRange { x: 32, y: 0, z: 0 })
    );
    assert!(c.set(0, usize::MAX, 0, STONE).is_err());
    assert!(c.fill_column(0, 0, 0..33, STONE).is_err());
    assert!(c.fill_column(0, 32, 0..3, STONE).is_err());
    assert!(c.fill_box([0; 3], [0, 0, 32], STONE).is_err());
    assert_eq!(c.as_uniform(), Some(AIR));
}

#[test]
fn uniform_chunks_store_one_value_and_collapse_back() {
    let mut c = Chunk::uniform(STONE);
    assert_eq!(c.memory_bytes(), std::mem::size_of::<Chunk>());
    c.set(5, 5, 5, AIR).unwrap();
    assert_eq!(c.as_uniform(), None);
    c.check_invariants().unwrap();
    c.set(5, 5, 5, STONE).unwrap();
    assert_eq!(c.as_uniform(), Some(STONE));
    c.fill_box([0; 3], [31; 3], WATER).unwrap();
    assert_eq!(c.as_uniform(), Some(WATER));
}

#[test]
fn column_fills_keep_masks_exact() {
    let mut c = Chunk::default();
    c.fill_column(4, 7, 0..20, STONE).unwrap();
    c.fill_column(4, 7, 18..25, WATER).unwrap();
    c.fill_column(4, 7, 3..3, SAND).unwrap();
    assert_eq!(
        c.occupancy(STONE).unwrap().by_y[column_index(4, 7)],
        (1 << 18) - 1
    );
    assert_eq!(
        c.occupancy(WATER).unwrap().by_y[column_index(4, 7)],
        ((1 << 25) - 1) & !((1 << 18) - 1)
    );
    assert!(c.occupancy(SAND).is_none());
    assert_eq!(c.count(STONE), 18);
    c.check_invariants().unwrap();
    c.fill_column(4, 7, 0..32, AIR).unwrap();
    assert_eq!(c.as_uniform(), Some(AIR));
}

#[test]
fn random_edits_match_a_dense_model() {
    let mut next = xorshift(0x2545_f491_4f6c_dd1d);
    let mut c = Chunk::default();
    let mut model = vec![AIR; CHUNK_VOLUME];
    for step in 0..20_000 {
        let r = next();
        let (x, y, z) = (
            r as usize % 32,
            (r >> 8) as usize % 32,
            (r >> 16) as usize % 32,
        );
        let id = BlockId((r >> 24) as u16 % 5);
        if step % 50 == 0 {
            let y1 = (y + (r >> 32) as usize % 8).min(32);
            c.fill_column(x, z, y..y1, id).unwrap();
            for yy in y..y1 {
                model[Chunk::dense_index(x, yy, z)] = id;
            }
        } else {
            c.set(x, y, z, id).unwrap();
            model[Chunk::dense_index(x, y, z)] = id;
        }
    }
    c.check_invariants().unwrap();
    assert_eq!(c.to_dense(), model);
}

/// A chunk of several types from a seed: boxes, columns and single blocks of up to
/// `types` ids (1..=types), on air.
fn varied_chunk(seed: u64, types: u16) -> Chunk {
    let mut next = xorshift(seed | 1);
    let mut c = Chunk::default();
    for step in 0..400 {
        let r = next();
        let p = [r % 32, (r >> 8) % 32, (r >> 16) % 32].map(|v| v as usize);
        let id = BlockId((r >> 24) as u16 % (types + 1));
        if step % 4 == 0 {
            let q = [(r >> 32) % 12, (r >> 40) % 12, (r >> 48) % 12]
                .map(|v| v as usize)
                .iter()
                .zip(&p)
                .map(|(e, p)| (p + e).min(31))
                .collect::<Vec<_>>();
            c.fill_box(p, [q[0], q[1], q[2]], id).unwrap();
        } else {
            c.set(p[0], p[1], p[2], id).unwrap();
        }
    }
    c
}

fn masks_by_id(c: &Chunk) -> Vec<(BlockId, Occupancy)> {
    let mut v: Vec<_> = c
        .stored_masks()
        .unwrap()
        .map(|(id, m)| (id, m.clone()))
        .collect();
    v.sort_by_key(|(id, _)| *id);
    v
}

#[test]
fn plane_counts_follow_the_palette() {
    let want = [
        (2, 1),
        (3, 2),
        (4, 2),
        (5, 3),
        (8, 3),
        (9, 4),
        (16, 4),
        (17, 5),
    ];
    for (len, planes) in want {
        assert_eq!(planes_for(len), planes, "{len} entries");
    }
}

#[test]
fn the_layout_transpose_turns_columns_into_rows() {
    let c = varied_chunk(7, 6);
    for (_, m) in c.stored_masks().unwrap() {
        let mut t = [0; CHUNK_AREA];
        transpose_layout_into(&m.by_y, &mut t);
        assert_eq!(t, m.by_x);
    }
    let mut a: LayerMask = std::array::from_fn(|i| (i as u32).wrapping_mul(0x9e37_79b9));
    let b = a;
    transpose32(&mut a);
    for (i, row) in b.iter().enumerate() {
        for (j, col) in a.iter().enumerate() {
            assert_eq!(col >> i & 1, row >> j & 1);
        }
    }
}

#[test]
fn pack_and_unpack_keep_every_block() {
    // Up to 21 types: five planes, past the vectorised decoding of up to four.
    for (seed, types) in [
        (1, 1),
        (2, 2),
        (3, 3),
        (4, 4),
        (5, 7),
        (6, 8),
        (7, 12),
        (8, 20),
    ] {
        let c = varied_chunk(seed, types);
        assert!(types < 20 || c.palette_len() > 16, "five planes");
        let mut p = c.clone();
        p.pack();
        assert!(p.is_packed() || c.as_uniform().is_some());
        p.check_invariants().unwrap();
        assert_eq!(p.to_dense(), c.to_dense(), "seed {seed}");
        assert_eq!(
            p.palette().collect::<Vec<_>>(),
            c.palette().collect::<Vec<_>>()
        );
        assert_eq!(p.palette_len(), c.palette_len());
        for id in 0..=types {
            assert_eq!(p.count(BlockId(id)), c.count(BlockId(id)));
            assert_eq!(p.occupancy(BlockId(id)), c.occupancy(BlockId(id)));
        }
        for (x, y, z) in [(0, 0, 0), (31, 31, 31), (5, 17, 30), (30, 2, 9)] {
            assert_eq!(p.get(x, y, z), c.get(x, y, z));
        }
        if c.as_uniform().is_none() {
            let bits = planes_for(c.palette_len());
            let data = bits * CHUNK_VOLUME / 8;
            assert!(p.memory_bytes() >= data && p.memory_bytes() < data + 256);
            assert!(p.memory_bytes() * 2 < c.memory_bytes());
        }
        p.pack();
        p.unpack();
        assert!(!p.is_packed());
        p.check_invariants().unwrap();
        if c.as_uniform().is_none() {
            assert_eq!(masks_by_id(&p), masks_by_id(&c));
        }
        p.unpack();
        assert_eq!(p.to_dense(), c.to_dense());
    }
}

#[test]
fn built_masks_and_side_layers_agree_across_forms() {
    for types in [9, 20] {
        let c = varied_chunk(11, types);
        assert!(
            c.palette_len() > 8 + 8 * usize::from(types > 9),
            "more planes than 3, 4"
        );
        built_masks_and_side_layers_agree(&c);
    }
}

fn built_masks_and_side_layers_agree(c: &Chunk) {
    let c = c.clone();
    let mut p = c.clone();
    p.pack();
    assert!(p.stored_masks().is_none());
    let mut buf = MaskBuffer::new();
    for chunk in [&c, &p] {
        chunk.build_masks(&mut buf, |id| id != BlockId::AIR);
        let want: Vec<_> = c
            .stored_masks()
            .unwrap()
            .filter(|(id, _)| *id != BlockId::AIR)
            .collect();
        assert_eq!(buf.len(), want.len());
        for ((a, ma), (b, mb)) in buf.iter().zip(want) {
            assert_eq!((a, ma), (b, mb));
        }
    }
    // Reused for a chunk of fewer types: only those are held.
    Chunk::uniform(STONE).build_masks(&mut buf, |_| true);
    assert_eq!(buf.iter().map(|(id, _)| id).collect::<Vec<_>>(), [STONE]);
    assert_eq!(buf.iter().next().unwrap().1, &FULL);
    let dense = c.to_dense();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for side in Face::ALL {
        c.side_layers(side, &mut a, |_| true);
        p.side_layers(side, &mut b, |_| true);
        let mut no_air = Vec::new();
        p.side_layers(side, &mut no_air, |id| id != AIR);
        assert_eq!(no_air.len() + 1, a.len());
        assert_eq!(a, b, "{side:?}");
        let l = side_index(side);
        for (id, rows) in &a {
            for (r, row) in rows.iter().enumerate() {
                for bit in 0..32 {
                    let [x, y, z] = match side.axis() {
                        0 => [l, bit, r],
                        1 => [bit, l, r],
                        _ => [bit, r, l],
                    };
                    let here = dense[Chunk::dense_index(x, y, z)] == *id;
                    assert_eq!(row >> bit & 1 == 1, here, "{side:?} {x} {y} {z}");
                }
            }
        }
    }
    Chunk::uniform(WATER).side_layers(Face::NegY, &mut a, |_| true);
    assert_eq!(a, vec![(WATER, [u32::MAX; 32])]);
}

#[test]
fn packed_planes_grow_and_narrow_with_the_palette() {
    let mut c = Chunk::default();
    c.set(0, 0, 0, STONE).unwrap();
    c.pack();
    c.check_invariants().unwrap();
    let one_plane = c.memory_bytes();
    // Types 2..=8 (ids up to 8): 9 types need 4 planes.
    for i in 2..=8u16 {
        c.set(usize::from(i), 3, 4, BlockId(i)).unwrap();
        c.check_invariants().unwrap();
    }
    assert!(c.is_packed());
    assert_eq!(c.palette_len(), 9);
    assert!(c.memory_bytes() >= one_plane + 3 * 4096);
    // Remove all but air and one type: back to one plane.
    for i in 2..=8 {
        c.set(i, 3, 4, AIR).unwrap();
        c.check_invariants().unwrap();
    }
    assert_eq!(c.palette_len(), 2);
    assert!(c.memory_bytes() <= one_plane + 256, "{}", c.memory_bytes());
    // Removing a type from the middle of the palette relabels the last one.
    c.fill_box([0, 10, 0], [3, 12, 3], WATER).unwrap();
    c.fill_box([5, 10, 5], [6, 12, 6], GLASS).unwrap();
    c.set(0, 0, 0, AIR).unwrap();
    c.check_invariants().unwrap();
    assert_eq!(c.count(STONE), 0);
    assert_eq!(c.get(0, 11, 0).unwrap(), WATER);
    assert_eq!(c.get(6, 12, 6).unwrap(), GLASS);
    assert_eq!(c.count(GLASS), 2 * 3 * 2);
    // A packed chunk filled with one type becomes uniform.
    c.fill_box([0; 3], [31; 3], SAND).unwrap();
    assert_eq!(c.as_uniform(), Some(SAND));
}

#[test]
fn random_edits_of_packed_chunks_match_a_dense_model() {
    let mut next = xorshift(0x1234_5678_9abc_def1);
    let mut c = varied_chunk(99, 6);
    let mut model = c.to_dense();
    c.pack();
    for step in 0..20_000 {
        let r = next();
        let (x, y, z) = (
            r as usize % 32,
            (r >> 8) as usize % 32,
            (r >> 16) as usize % 32,
        );
        // Up to 11 types at once, so that the planes grow and narrow.
        let id = BlockId((r >> 24) as u16 % if step % 5000 < 2500 { 3 } else { 11 });
        if step % 50 == 0 {
            let y1 = (y + (r >> 32) as usize % 8).min(32);
            c.fill_column(x, z, y..y1, id).unwrap();
            for yy in y..y1 {
                model[Chunk::dense_index(x, yy, z)] = id;
            }
        } else if step % 997 == 0 {
            let m = [x, y, z].map(|v| (v + 6).min(31));
            c.fill_box([x, y, z], m, id).unwrap();
            for xx in x..=m[0] {
                for yy in y..=m[1] {
                    for zz in z..=m[2] {
                        model[Chunk::dense_index(xx, yy, zz)] = id;
                    }
                }
            }
        } else {
            assert_eq!(
                c.set(x, y, z, id).unwrap(),
                model[Chunk::dense_index(x, y, z)]
            );
            model[Chunk::dense_index(x, y, z)] = id;
        }
        if step % 1000 == 0 {
            c.check_invariants().unwrap();
            if c.as_uniform().is_none() {
                assert!(c.is_packed(), "edits keep the packed form");
            }
        }
    }
    c.check_invariants().unwrap();
    assert_eq!(c.to_dense(), model);
}
