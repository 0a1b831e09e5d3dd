//! The contract (see the module docs), against an oracle written without the streamer's
//! code.

use super::*;
use crate::Error;

/// What a test source makes at a position.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// Blocks (deterministic from the position, or from each call).
    Blocks,
    /// The source panics.
    Panics,
    /// The source makes a block id the registry does not hold.
    Unknown,
}

fn mix(mut h: u64) -> u64 {
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

fn hash(pos: ChunkPos, salt: u64) -> u64 {
    let p = |v: i32| u64::from(v as u32);
    mix(p(pos.x) ^ mix(p(pos.y) ^ mix(p(pos.z) ^ mix(salt))))
}

/// The blocks a test source makes for `pos` from `seed`: air, uniform stone or water,
/// or a few small boxes of stone, glass, water, leaves and red glass, many of them on
/// the chunk's faces, edges and corners (where the neighbours' meshes read them).
fn blocks_of(pos: ChunkPos, seed: u64) -> Chunk {
    let h = hash(pos, seed);
    match h % 10 {
        0..=2 => Chunk::default(),
        3 => Chunk::uniform(if pos.y < 0 {
            blocks::STONE
        } else {
            BlockId::AIR
        }),
        4 => Chunk::uniform(blocks::WATER),
        _ => {
            let mut next = crate::arena::tests::rng(h | 1);
            let mut c = Chunk::default();
            let ids = [
                blocks::STONE,
                blocks::GLASS,
                blocks::WATER,
                blocks::LEAVES,
                blocks::RED_GLASS,
            ];
            for _ in 0..(next() % 6 + 1) {
                let id = ids[(next() % 5) as usize];
                let corner = |r: u64| match r % 4 {
                    0 => 0,
                    1 => 31 - (r / 4 % 3) as usize,
                    _ => (r / 4 % 32) as usize,
                };
                let lo = [corner(next()), corner(next()), corner(next())];
                let size = [next() % 4, next() % 4, next() % 4];
                for x in lo[0]..=(lo[0] + size[0] as usize).min(31) {
                    for y in lo[1]..=(lo[1] + size[1] as usize).min(31) {
                        for z in lo[2]..=(lo[2] + size[2] as usize).min(31) {
                            let _ = c.set(x, y, z, id);
                        }
                    }
                }
            }
            c
        }
    }
}

/// Which positions fail, with `failing` set: one in 17 panics, one in 17 makes an
/// unknown id.
fn kind_of(pos: ChunkPos, failing: bool) -> Kind {
    match hash(pos, 99) % 17 {
        0 if failing => Kind::Panics,
        1 if failing => Kind::Unknown,
        _ => Kind::Blocks,
    }
}

/// The test source: `blocks_of` from a fixed seed, or from a new seed each call
/// (`changing`), failing where [`kind_of`] says.
struct TestSource {
    failing: bool,
    changing: Option<std::sync::atomic::AtomicU64>,
}

impl ChunkSource for TestSource {
    fn generate(&self, pos: ChunkPos) -> Chunk {
        match kind_of(pos, self.failing) {
            Kind::Panics => panic!("test source: broken at {pos:?}"),
            Kind::Unknown => Chunk::uniform(BlockId(60_000)),
            Kind::Blocks => {
                let seed = self
                    .changing
                    .as_ref()
                    .map_or(7, |n| n.fetch_add(1, Ordering::Relaxed) + 1000);
                blocks_of(pos, seed)
            }
        }
    }
}

/// The true world of a deterministic test source: its blocks (air where it fails) with
/// every edit applied in order. Written from the contract, not from the streamer.
struct Truth {
    failing: bool,
    edits: HashMap<ChunkPos, Vec<([usize; 3], BlockId)>>,
    /// The chunks and fresh meshes made so far, kept until the next edit: every check
    /// after a settle reads most of them again.
    chunks: std::cell::RefCell<HashMap<ChunkPos, Chunk>>,
    meshes: std::cell::RefCell<HashMap<ChunkPos, ChunkMeshes>>,
}

impl Truth {
    fn new(failing: bool) -> Self {
        Self {
            failing,
            edits: HashMap::new(),
            chunks: Default::default(),
            meshes: Default::default(),
        }
    }

    /// The chunk at `pos`, made once until an edit.
    fn cached(&self, pos: ChunkPos) -> Chunk {
        self.chunks
            .borrow_mut()
            .entry(pos)
            .or_insert_with(|| self.chunk(pos))
            .clone()
    }

    /// A fresh mesh of `pos` (`fresh_mesh`), made once until an edit.
    fn fresh_mesh(&self, pos: ChunkPos) -> ChunkMeshes {
        if let Some(m) = self.meshes.borrow().get(&pos) {
            return m.clone();
        }
        let m = fresh_mesh(pos, &|p| Some(self.cached(p)));
        self.meshes.borrow_mut().insert(pos, m.clone());
        m
    }

    fn chunk(&self, pos: ChunkPos) -> Chunk {
        if kind_of(pos, self.failing) != Kind::Blocks {
            return Chunk::default();
        }
        let mut c = blocks_of(pos, 7);
        for &([x, y, z], id) in self.edits.get(&pos).into_iter().flatten() {
            let _ = c.set(x, y, z, id);
        }
        c
    }

    fn block(&self, pos: WorldPos) -> BlockId {
        let (c, [x, y, z]) = pos.split();
        self.chunk(c).get(x, y, z).unwrap_or(BlockId::AIR)
    }

    fn edit(&mut self, pos: WorldPos, id: BlockId) {
        self.chunks.get_mut().clear();
        self.meshes.get_mut().clear();
        let (c, local) = pos.split();
        self.edits.entry(c).or_default().push((local, id));
    }
}

/// A fresh mesh of `pos` from `chunk_at` (its 26 neighbours included).
fn fresh_mesh(pos: ChunkPos, chunk_at: &dyn Fn(ChunkPos) -> Option<Chunk>) -> ChunkMeshes {
    let centre = chunk_at(pos).unwrap_or_default();
    let around: Vec<Option<Chunk>> = Neighbourhood::OFFSETS
        .iter()
        .map(|&d| pos.offset(d).and_then(chunk_at))
        .collect();
    let mut mesher = Mesher::new(&registry());
    let nb = Neighbourhood::from_fn(|d| {
        let i = Neighbourhood::OFFSETS.iter().position(|&o| o == d)?;
        around[i].as_ref()
    });
    mesher.mesh(&centre, nb).unwrap()
}

/// A sink holding every chunk's meshes, as the renderer would.
#[derive(Default)]
struct Holder {
    held: HashMap<ChunkPos, ChunkMeshes>,
}

impl ChunkSink for Holder {
    fn upload(&mut self, pos: ChunkPos, meshes: &ChunkMeshes) -> Result<()> {
        assert!(!meshes.is_empty(), "empty meshes uploaded at {pos:?}");
        self.held.insert(pos, meshes.clone());
        Ok(())
    }

    fn remove(&mut self, pos: ChunkPos) {
        assert!(
            self.held.remove(&pos).is_some(),
            "removed {pos:?}, not held"
        );
    }
}

/// Updates until idle; `None` if not within `limit` updates. Collects the failures
/// reported.
fn run_to_idle(
    s: &mut ChunkStreamer,
    eye: DVec3,
    sink: &mut Holder,
    failed: &mut HashSet<ChunkPos>,
    limit: usize,
) -> Option<usize> {
    for i in 0..limit {
        let f = s.update(eye, sink).unwrap();
        failed.extend(f.failed.iter().map(|x| x.0));
        if s.is_idle() {
            return Some(i);
        }
        if s.jobs() > 0 {
            std::thread::sleep(std::time::Duration::from_micros(30));
        }
    }
    None
}

/// The contract's checks once idle: the sink holds exactly the true world's fresh
/// meshes, every chunk within the view distance that has faces, nothing past the
/// margin; resident blocks equal the true world's; failures were reported.
fn check_against_truth(
    s: &ChunkStreamer,
    sink: &Holder,
    truth: &Truth,
    eye: DVec3,
    failed: &HashSet<ChunkPos>,
    what: &str,
) {
    let centre = ChunkStreamer::centre_of(eye).unwrap();
    for (&pos, meshes) in &sink.held {
        assert!(s.keeps(pos, centre), "{what}: {pos:?} past the margin");
        let fresh = truth.fresh_mesh(pos);
        assert!(
            *meshes == fresh,
            "{what}: {pos:?} drawn with {} quads, a fresh mesh of the true world has {}",
            meshes.len(),
            fresh.len()
        );
    }
    for o in &s.offsets {
        let pos = ChunkPos::new(centre.x + o[0], centre.y + o[1], centre.z + o[2]);
        if !sink.held.contains_key(&pos) {
            let fresh = truth.fresh_mesh(pos);
            assert!(
                fresh.is_empty(),
                "{what}: {pos:?} within the view distance not drawn ({} quads)",
                fresh.len()
            );
        }
        if kind_of(pos, truth.failing) != Kind::Blocks {
            assert!(failed.contains(&pos), "{what}: {pos:?} failed unreported");
        }
    }
    for (pos, c) in s.world().iter() {
        let t = truth.cached(pos);
        if same_blocks(c, &t) {
            continue;
        }
        // Every block, in `to_dense`'s order: y fastest, then z, then x.
        let (have, want) = (c.to_dense(), t.to_dense());
        if let Some(i) = (0..have.len()).find(|&i| have[i] != want[i]) {
            let (x, y, z) = (
                i / CHUNK_SIZE / CHUNK_SIZE,
                i % CHUNK_SIZE,
                i / CHUNK_SIZE % CHUNK_SIZE,
            );
            panic!(
                "{what}: resident block {x},{y},{z} of {pos:?} is {:?}, the true world's {:?}",
                have[i], want[i]
            );
        }
    }
}

/// Whether `a` and `b` hold the same blocks, in whatever form each is stored: as many
/// blocks of each type, at the same places (air is what the other types leave).
fn same_blocks(a: &Chunk, b: &Chunk) -> bool {
    let palette = |c: &Chunk| {
        let mut p: Vec<(BlockId, usize)> = c.palette().filter(|e| e.1 > 0).collect();
        p.sort_unstable_by_key(|e| e.0.0);
        p
    };
    let pa = palette(a);
    pa == palette(b)
        && pa
            .iter()
            .all(|&(id, _)| id == BlockId::AIR || a.occupancy(id) == b.occupancy(id))
}

/// For a source that answers differently each call there is no true world beyond what
/// the streamer holds: every drawn chunk equals a fresh mesh of the streamer's own
/// resident blocks, all 26 of its neighbours resident, and every chunk within the view
/// distance whose fresh mesh of those blocks has faces is drawn.
fn check_against_own_world(s: &ChunkStreamer, sink: &Holder, eye: DVec3, what: &str) {
    let chunk_at = |p: ChunkPos| s.world().chunk(p).cloned();
    let centre = ChunkStreamer::centre_of(eye).unwrap();
    for o in &s.offsets {
        let pos = ChunkPos::new(centre.x + o[0], centre.y + o[1], centre.z + o[2]);
        if !sink.held.contains_key(&pos) {
            let fresh = fresh_mesh(pos, &chunk_at);
            assert!(
                fresh.is_empty(),
                "{what}: {pos:?} within the view distance not drawn ({} quads)",
                fresh.len()
            );
        }
    }
    for (&pos, meshes) in &sink.held {
        for d in Neighbourhood::OFFSETS {
            let n = pos.offset(d).unwrap();
            assert!(
                s.is_resident(n),
                "{what}: {pos:?} drawn, neighbour {n:?} not held"
            );
        }
        assert!(
            *meshes == fresh_mesh(pos, &chunk_at),
            "{what}: {pos:?} differs from a fresh mesh of the streamer's own world"
        );
    }
}

/// A block position in chunk `c`: on a face, edge or corner (or inside) at random.
fn block_in(c: ChunkPos, next: &mut impl FnMut() -> u64) -> WorldPos {
    let o = c.origin();
    let local = |r: u64| match r % 3 {
        0 => 0,
        1 => 31,
        _ => (r / 3 % 32) as i64,
    };
    WorldPos::new(
        (o[0] + local(next())) as i32,
        (o[1] + local(next())) as i32,
        (o[2] + local(next())) as i32,
    )
}

/// Random sequences of moves, teleports (away and back), view-distance changes, partial
/// updates and edits (near the eye, on chunks at the view-distance edge and just past
/// it, on chunks not loaded next to loaded ones and far away, on failing chunks), with
/// sources that are deterministic, fail (panic, unknown ids) or change on each call.
/// Now and then, and at the end, the streamer must become idle and then hold the
/// truth (see the module docs).
#[test]
fn random_sequences_hold_the_truth_once_idle() {
    let mut checks = 0;
    let mut edits_made = [0usize; 5];
    for seq in 0..36u64 {
        let mut next = crate::arena::tests::rng(0x5eed_0000 + seq * 7919);
        let failing = seq % 3 == 1;
        let changing = seq % 3 == 2;
        let config = StreamConfig {
            view_distance: 1 + (seq % 3) as u32,
            vertical_distance: 1,
            hysteresis: 1 + (seq % 2) as u32,
            threads: 2,
            max_jobs: [1, 4, 64][(seq % 3) as usize],
            max_unloads: [1, 7, 256][(seq / 3 % 3) as usize],
            scan_budget: [3, 2048][(seq % 2) as usize],
            upload_budget_bytes: [64, 1 << 20][(seq / 2 % 2) as usize],
            local_budget: std::time::Duration::from_micros([0, 300, 4000][(seq / 4 % 3) as usize]),
        };
        let source = TestSource {
            failing,
            changing: changing.then(|| std::sync::atomic::AtomicU64::new(0)),
        };
        // One sequence in four with its jobs on the updating thread (a browser page's).
        let mut s = if seq % 4 == 3 {
            ChunkStreamer::new_local(registry(), source, config).unwrap()
        } else {
            ChunkStreamer::new(registry(), source, config).unwrap()
        };
        let mut truth = Truth::new(failing);
        let mut sink = Holder::default();
        let mut failed = HashSet::new();
        let home = DVec3::new(5.0, 10.0, 5.0);
        let mut eye = home;
        for step in 0..40 {
            let what = format!("sequence {seq} step {step}");
            let centre = ChunkStreamer::centre_of(eye).unwrap();
            let r = next() % 100;
            match r {
                0..=14 => {
                    let d = |n: u64| (n % 65) as f64 - 32.0;
                    eye += DVec3::new(d(next()), d(next()) / 4.0, d(next()));
                }
                15..=19 => {
                    // Far away, a few chunks away (past the view distance, within
                    // or past the margin: chunks leave the sink but stay resident
                    // for their neighbours), or back home (flying away and back).
                    let k = f64::from(1 + (next() % 8) as u32) * 32.0;
                    eye = match next() % 3 {
                        0 => home + DVec3::new(32.0 * 40.0, 0.0, -32.0 * 25.0),
                        1 => home + DVec3::new(k, 0.0, -((next() % 2) as f64) * k),
                        _ => home,
                    };
                }
                20..=22 => {
                    let mut c = *s.config();
                    c.view_distance = 1 + (next() % 3) as u32;
                    s.set_config(c).unwrap();
                }
                23..=39 => {
                    for _ in 0..next() % 4 {
                        let f = s.update(eye, &mut sink).unwrap();
                        failed.extend(f.failed.iter().map(|x| x.0));
                    }
                }
                _ => {
                    // An edit: which chunk, by kind.
                    let vd = i32::try_from(s.config().view_distance).unwrap();
                    let kind = (next() % 5) as usize;
                    let c = match kind {
                        // Near the eye.
                        0 => ChunkPos::new(
                            centre.x + (next() % 3) as i32 - 1,
                            centre.y + (next() % 3) as i32 - 1,
                            centre.z + (next() % 3) as i32 - 1,
                        ),
                        // At the view-distance edge, or one or two past it.
                        1 => {
                            let out = vd + (next() % 3) as i32;
                            let side =
                                [(out, 0), (-out, 0), (0, out), (0, -out)][(next() % 4) as usize];
                            ChunkPos::new(centre.x + side.0, centre.y, centre.z + side.1)
                        }
                        // Just past the margin, next to the loaded ring.
                        2 => ChunkPos::new(
                            centre.x + vd + 3 + (next() % 2) as i32,
                            centre.y,
                            centre.z,
                        ),
                        // Far away, not loaded.
                        3 => ChunkPos::new(
                            centre.x + 60 + (next() % 5) as i32,
                            centre.y,
                            centre.z - 40,
                        ),
                        // Around home, wherever the eye is.
                        _ => ChunkPos::new(
                            (next() % 5) as i32 - 2,
                            (next() % 3) as i32 - 1,
                            (next() % 5) as i32 - 2,
                        ),
                    };
                    let at = block_in(c, &mut next);
                    let id = [
                        BlockId::AIR,
                        blocks::STONE,
                        blocks::GLASS,
                        blocks::WATER,
                        blocks::LEAVES,
                    ][(next() % 5) as usize];
                    let expected_old = truth.block(at);
                    match s.set_block(at, id) {
                        Ok(old) => {
                            assert_eq!(kind_of(c, failing), Kind::Blocks, "{what}");
                            if !changing {
                                assert_eq!(old, expected_old, "{what}: old block at {at:?}");
                            }
                            truth.edit(at, id);
                            edits_made[kind] += 1;
                        }
                        Err(e) => {
                            assert!(matches!(e, Error::ChunkSource { .. }), "{what}: {e}");
                            assert_ne!(kind_of(c, failing), Kind::Blocks, "{what}: {e}");
                        }
                    }
                }
            }
            if step % 13 == 12 || step == 39 {
                let idle = run_to_idle(&mut s, eye, &mut sink, &mut failed, 20_000);
                assert!(idle.is_some(), "{what}: never idle: {s:?}");
                if changing {
                    check_against_own_world(&s, &sink, eye, &what);
                } else {
                    check_against_truth(&s, &sink, &truth, eye, &failed, &what);
                }
                assert!(s.queued_unloads() <= s.positions());
                checks += 1;
            }
        }
    }
    assert!(checks >= 36 * 4, "{checks} checks");
    // Every kind of edit was made, many times.
    assert!(edits_made.iter().all(|&n| n >= 20), "{edits_made:?}");
}

fn deterministic(view_distance: u32, hysteresis: u32) -> (ChunkStreamer, Truth) {
    let config = StreamConfig {
        view_distance,
        vertical_distance: 1,
        hysteresis,
        threads: 2,
        ..StreamConfig::default()
    };
    let source = TestSource {
        failing: false,
        changing: None,
    };
    let s = ChunkStreamer::new(registry(), source, config).unwrap();
    let truth = Truth::new(false);
    (s, truth)
}

/// Runs to idle (within `limit` updates) and checks the contract.
fn settle_and_check(
    s: &mut ChunkStreamer,
    sink: &mut Holder,
    truth: &Truth,
    eye: DVec3,
    limit: usize,
    what: &str,
) {
    let mut failed = HashSet::new();
    let idle = run_to_idle(s, eye, sink, &mut failed, limit);
    assert!(
        idle.is_some(),
        "{what}: not idle after {limit} updates: {s:?}"
    );
    check_against_truth(s, sink, truth, eye, &failed, what);
}

/// The middle of chunk `c` at height 10, as an eye.
fn eye_in(c: ChunkPos) -> DVec3 {
    DVec3::new(
        f64::from(c.x) * 32.0 + 16.0,
        f64::from(c.y) * 32.0 + 10.0,
        f64::from(c.z) * 32.0 + 16.0,
    )
}

/// [`deterministic`] (view distance 2, hysteresis 1) settled with the eye in chunk 0, then
/// two chunks along -x, settled and checked: chunk (2, 0, 0) is 4 away there, at the
/// margin's edge (2 + 2); (3, 0, 0) lies past it. The streamer, the truth, the sink and
/// the eye.
fn moved_two_chunks_along_minus_x() -> (ChunkStreamer, Truth, Holder, DVec3) {
    let (mut s, truth) = deterministic(2, 1);
    let mut sink = Holder::default();
    let at_0 = eye_in(ChunkPos::new(0, 0, 0));
    settle_and_check(&mut s, &mut sink, &truth, at_0, 5_000, "at 0");
    let eye = eye_in(ChunkPos::new(-2, 0, 0));
    settle_and_check(&mut s, &mut sink, &truth, eye, 5_000, "moved");
    (s, truth, sink, eye)
}

/// The eye flies two chunks away and back (the outer neighbour of the
/// chunk at the view-distance edge passed the margin meanwhile), then a block is placed
/// on that chunk's outer face: it is drawn and the streamer becomes idle (before, the
/// remesh waited for the neighbour for ever and the old mesh stayed). Then far away and
/// back: still there.
#[test]
fn an_edit_at_the_view_distance_edge_after_flying_away_and_back_is_drawn() {
    let (mut s, mut truth) = deterministic(2, 1);
    let mut sink = Holder::default();
    let home = eye_in(ChunkPos::new(0, 0, 0));
    settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "loaded");
    settle_and_check(
        &mut s,
        &mut sink,
        &truth,
        eye_in(ChunkPos::new(-2, 0, 0)),
        5_000,
        "away",
    );
    settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "back");
    for at in [
        WorldPos::new(2 * 32 + 31, 5, 7),
        WorldPos::new(2 * 32 + 31, 31, 0),
    ] {
        s.set_block(at, blocks::RED_GLASS).unwrap();
        truth.edit(at, blocks::RED_GLASS);
    }
    settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "edited");
    assert!(sink.held.contains_key(&ChunkPos::new(2, 0, 0)));
    settle_and_check(
        &mut s,
        &mut sink,
        &truth,
        eye_in(ChunkPos::new(50, 0, 0)),
        5_000,
        "far",
    );
    settle_and_check(&mut s, &mut sink, &truth, home, 5_000, "home again");
}

/// Return trips of every length, at view distances 3, 8 and 16 (vertical 1, default
/// hysteresis): from home the eye flies `k` chunks away (along an axis or a diagonal),
/// settles, flies back and settles, for every `k` from 1 to past the margin. Each stop
/// is checked against the true world. Chunks past the view distance leave the sink but
/// stay resident while a neighbour still needs their blocks; once wanted again they
/// must be meshed and uploaded again (they were left as done: a hole beside the eye).
#[test]
fn return_trips_of_every_length_hold_the_truth() {
    for view_distance in [3u32, 8, 16] {
        let (mut s, truth) = deterministic(view_distance, StreamConfig::default().hysteresis);
        let mut sink = Holder::default();
        let home = eye_in(ChunkPos::new(0, 0, 0));
        let what = format!("view distance {view_distance}");
        settle_and_check(&mut s, &mut sink, &truth, home, 50_000, &what);
        let reach = view_distance as i32 + 2 * 2 + 2;
        for k in 1..=reach {
            let away = if k % 2 == 0 {
                ChunkPos::new(k, 0, 0)
            } else {
                ChunkPos::new(-k, 0, k / 2)
            };
            let what = format!("view distance {view_distance}, {away:?} and back");
            // The far stop is checked where the margin can matter; every return is.
            if view_distance < 16 || k > view_distance as i32 {
                settle_and_check(&mut s, &mut sink, &truth, eye_in(away), 50_000, &what);
            } else {
                let mut failed = HashSet::new();
                let idle = run_to_idle(&mut s, eye_in(away), &mut sink, &mut failed, 50_000);
                assert!(idle.is_some(), "{what}: not idle away: {s:?}");
            }
            settle_and_check(&mut s, &mut sink, &truth, home, 50_000, &what);
        }
    }
}

/// A chunk drawn at the edge of the margin, whose outer neighbour lies
/// past it, is edited: it is meshed again (its neighbour stayed resident for it) and the
/// streamer becomes idle (it never did: it waited for a neighbour nobody loaded).
#[test]
fn an_edit_of_a_chunk_whose_outer_neighbour_is_past_the_margin_is_remeshed() {
    let (mut s, mut truth, mut sink, eye) = moved_two_chunks_along_minus_x();
    let edge = ChunkPos::new(2, 0, 0);
    let outer = ChunkPos::new(3, 0, 0);
    let centre = ChunkStreamer::centre_of(eye).unwrap();
    assert!(s.keeps(edge, centre) && !s.keeps(outer, centre));
    assert!(
        !sink.held.contains_key(&edge) || s.is_resident(outer),
        "a drawn chunk's neighbour left memory"
    );
    for at in [
        WorldPos::new(2 * 32 + 31, 3, 3),
        WorldPos::new(2 * 32 + 31, 31, 31),
    ] {
        s.set_block(at, blocks::STONE).unwrap();
        truth.edit(at, blocks::STONE);
    }
    settle_and_check(&mut s, &mut sink, &truth, eye, 20_000, "edited");
}

/// The chunk just past the margin next to a drawn one is edited on the
/// face they share: the drawn chunk's border faces follow (its neighbour is resident,
/// so the edit remeshes it). And an edit of a chunk far away changes no drawn chunk.
#[test]
fn an_edit_beside_a_drawn_chunk_remeshes_its_border() {
    let (mut s, mut truth, mut sink, eye) = moved_two_chunks_along_minus_x();
    let outer = ChunkPos::new(3, 0, 0);
    // Fill the face of the outer chunk that touches chunk (2, 0, 0): every face of
    // the drawn chunk's border layer changes.
    for y in 0..32 {
        for z in 0..32 {
            let at = WorldPos::new(3 * 32, y, z);
            s.set_block(at, blocks::STONE).unwrap();
            truth.edit(at, blocks::STONE);
        }
    }
    let far = WorldPos::new(40 * 32 + 3, 4, 5);
    s.set_block(far, blocks::GLASS).unwrap();
    truth.edit(far, blocks::GLASS);
    settle_and_check(&mut s, &mut sink, &truth, eye, 5_000, "edited");
    assert!(s.is_resident(outer) || !sink.held.contains_key(&ChunkPos::new(2, 0, 0)));
}

/// A source that answers differently on each call; flying away and
/// back, every drawn chunk still equals a fresh mesh of the streamer's own blocks (a
/// neighbour generated anew under a drawn chunk left it stale).
#[test]
fn a_source_that_changes_leaves_no_stale_mesh() {
    let config = StreamConfig {
        view_distance: 3,
        vertical_distance: 1,
        hysteresis: 1,
        threads: 2,
        max_unloads: 5,
        ..StreamConfig::default()
    };
    let source = TestSource {
        failing: false,
        changing: Some(std::sync::atomic::AtomicU64::new(0)),
    };
    let mut s = ChunkStreamer::new(registry(), source, config).unwrap();
    let mut sink = Holder::default();
    let mut failed = HashSet::new();
    for (i, c) in [0, 3, 6, 9, 4, 0, -5, 0].into_iter().enumerate() {
        let eye = eye_in(ChunkPos::new(c, 0, c / 2));
        // Half the way settled, half not: chunks unload and reload in between.
        let limit = if i % 2 == 0 { 20_000 } else { 40 };
        let idle = run_to_idle(&mut s, eye, &mut sink, &mut failed, limit);
        if limit == 20_000 {
            assert!(idle.is_some(), "not idle: {s:?}");
            check_against_own_world(&s, &sink, eye, &format!("stop {i}"));
        }
    }
}

/// An edit of a chunk whose source panics or makes unknown ids
/// is an error (the panic never reaches the caller), whether the chunk is not loaded,
/// on its way, or loaded (where it stands as air, reported by the update).
#[test]
fn edits_of_chunks_whose_source_fails_are_errors() {
    let config = StreamConfig {
        view_distance: 3,
        vertical_distance: 1,
        threads: 1,
        max_jobs: 1,
        ..StreamConfig::default()
    };
    let mut s = ChunkStreamer::new(registry(), Broken, config).unwrap();
    let mut sink = Holder::default();
    // (1, 0, 0) panics, (-1, 0, 0) makes unknown ids; far copies of them too.
    for c in [1, -1] {
        let at = WorldPos::new(c * 32 + 4, 4, 4);
        let e = s.set_block(at, blocks::GLASS).unwrap_err();
        assert!(matches!(e, Error::ChunkSource { .. }), "{e:?}");
        let msg = e.to_string();
        assert!(msg.contains(&format!("x: {c}")), "{msg}");
        assert!(
            msg.contains(if c == 1 { "panicked" } else { "unknown" }),
            "{msg}"
        );
    }
    // On their way: one job at a time, so both are still generating after an update.
    s.update(DVec3::splat(16.0), &mut sink).unwrap();
    for c in [1, -1] {
        assert!(
            s.set_block(WorldPos::new(c * 32 + 4, 4, 4), blocks::GLASS)
                .is_err()
        );
    }
    let mut failed = HashSet::new();
    run_to_idle(&mut s, DVec3::splat(16.0), &mut sink, &mut failed, 20_000).unwrap();
    assert!(failed.contains(&ChunkPos::new(1, 0, 0)) && failed.contains(&ChunkPos::new(-1, 0, 0)));
    for c in [1, -1] {
        let e = s
            .set_block(WorldPos::new(c * 32 + 4, 4, 4), blocks::GLASS)
            .unwrap_err();
        assert!(e.to_string().contains("stands as air"), "{e}");
        assert!(!sink.held.contains_key(&ChunkPos::new(c, 0, 0)));
    }
    // Their neighbours draw; an edit next to them works.
    assert!(sink.held.contains_key(&ChunkPos::new(0, 0, 0)));
    s.set_block(WorldPos::new(31, 5, 5), blocks::STONE).unwrap();
}

/// The unload queue holds each chunk once. After a teleport, the eye
/// moves to a new chunk every update while unloads trickle (one per update): the queue
/// never holds more than the positions known (it used to take every far chunk again
/// on every move: 730 MiB and 292 ms updates at view distance 64).
#[test]
fn the_unload_queue_holds_each_chunk_once() {
    let config = StreamConfig {
        view_distance: 6,
        vertical_distance: 1,
        max_unloads: 1,
        threads: 1,
        ..StreamConfig::default()
    };
    let mut s = ChunkStreamer::new(registry(), Pillars, config).unwrap();
    let mut sink = Recorder::default();
    settle(&mut s, DVec3::splat(16.0), &mut sink, 20_000);
    let loaded = s.positions();
    let mut most = 0;
    for i in 0..300 {
        let eye = DVec3::new(16.0 + 32.0 * (5_000.0 + f64::from(i)), 16.0, 16.0);
        s.update(eye, &mut sink).unwrap();
        assert!(s.queued_unloads() <= s.positions(), "update {i}: {s:?}");
        most = most.max(s.queued_unloads());
    }
    assert!(most <= loaded + s.positions(), "{most}");
    // And it all drains: the old place leaves memory, the new one loads.
    let eye = DVec3::new(16.0 + 32.0 * 5_300.0, 16.0, 16.0);
    settle(&mut s, eye, &mut sink, 50_000);
    let centre = ChunkPos::new(5_300, 0, 0);
    assert!(s.world().iter().all(|(p, _)| (p.x - centre.x).abs() < 20));
}

/// A source that counts its calls and takes 2 ms each.
struct Slow(Arc<std::sync::atomic::AtomicUsize>);

impl ChunkSource for Slow {
    fn generate(&self, _: ChunkPos) -> Chunk {
        std::thread::sleep(std::time::Duration::from_millis(2));
        self.0.fetch_add(1, Ordering::SeqCst);
        Chunk::uniform(blocks::STONE)
    }
}

/// Dropping the streamer with 64 jobs queued stops them: at most the
/// one running goes on (they all ran, 64 calls, before).
#[test]
fn dropping_the_streamer_stops_its_jobs() {
    let calls = Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let config = StreamConfig {
        view_distance: 8,
        threads: 1,
        max_jobs: 64,
        ..StreamConfig::default()
    };
    let mut s = ChunkStreamer::new(registry(), Slow(calls.clone()), config).unwrap();
    s.update(DVec3::splat(16.0), &mut Recorder::default())
        .unwrap();
    assert_eq!(s.jobs(), 64);
    drop(s);
    let at_drop = calls.load(Ordering::SeqCst);
    std::thread::sleep(std::time::Duration::from_millis(300));
    let after = calls.load(Ordering::SeqCst);
    assert!(
        after <= at_drop + 1,
        "{at_drop} calls at the drop, {after} after"
    );
}

/// 10 000 edits of chunks far away are kept as edits, within the
/// documented bound (they took 135 MB as whole chunks), and each comes back when its
/// chunk loads; the edit list reports them for saving.
#[test]
fn far_edits_are_kept_within_the_bound() {
    let mut s = ChunkStreamer::new(registry(), Pillars, config(1)).unwrap();
    let mut sink = Recorder::default();
    settle(&mut s, DVec3::splat(16.0), &mut sink, 10_000);
    let before = s.memory_bytes();
    let at = |i: i32| WorldPos::new(1000 * 32 + (i % 100) * 64 + 3, 7, (i / 100) * 64 + 9);
    for i in 0..10_000 {
        assert_eq!(s.set_block(at(i), blocks::GLASS).unwrap(), BlockId::AIR);
    }
    let kept = s.memory_bytes() - before;
    assert_eq!(kept, s.edit_bytes());
    assert_eq!(kept, 10_000 * (EDIT_BYTES + EDITED_CHUNK_BYTES));
    assert!(kept < 2 << 20, "{kept} bytes");
    assert_eq!(s.edits().count(), 10_000);
    assert!(
        s.edits()
            .any(|(p, id)| p == at(4321) && id == blocks::GLASS)
    );
    // One of them, loaded: the glass is there, drawn.
    let (c, [x, y, z]) = at(4321).split();
    let eye = DVec3::new(
        f64::from(c.x) * 32.0 + 16.0,
        16.0,
        f64::from(c.z) * 32.0 + 16.0,
    );
    settle(&mut s, eye, &mut sink, 20_000);
    assert_eq!(
        s.world().chunk(c).unwrap().get(x, y, z).unwrap(),
        blocks::GLASS
    );
    assert!(sink.held.contains_key(&c));
}

/// The oracle's block comparison: the same blocks in another form are the same, one block
/// moved or changed is not.
#[test]
fn same_blocks_compares_every_block_in_any_form() {
    // A chunk of boxes of several types.
    let a = (0..100)
        .map(|x| blocks_of(ChunkPos::new(x, 0, 0), 7))
        .find(|c| c.palette_len() > 2)
        .unwrap();
    let mut packed = a.clone();
    packed.pack();
    assert!(same_blocks(&a, &packed) && same_blocks(&packed, &a));
    let mut changed = packed.clone();
    let old = changed.get(0, 0, 0).unwrap();
    let other = if old == blocks::STONE {
        blocks::GLASS
    } else {
        blocks::STONE
    };
    changed.set(0, 0, 0, other).unwrap();
    assert!(!same_blocks(&a, &changed));
    // The same counts at other places.
    let mut moved = Chunk::default();
    moved.set(1, 0, 0, blocks::STONE).unwrap();
    let mut here = Chunk::default();
    here.set(0, 0, 0, blocks::STONE).unwrap();
    assert!(!same_blocks(&here, &moved));
    assert!(same_blocks(
        &Chunk::uniform(blocks::WATER),
        &Chunk::uniform(blocks::WATER)
    ));
    assert!(!same_blocks(
        &Chunk::uniform(blocks::WATER),
        &Chunk::default()
    ));
}

/// The contract holds where the jobs run on the updating thread (a browser page's
/// streamer, wasm32): a route of return trips and edits, each checked against the true
/// world once idle, with no thread started.
#[test]
fn a_local_streamer_holds_the_truth_once_idle() {
    let config = StreamConfig {
        view_distance: 3,
        vertical_distance: 1,
        hysteresis: 1,
        local_budget: std::time::Duration::from_millis(2),
        ..StreamConfig::default()
    };
    let source = TestSource {
        failing: true,
        changing: None,
    };
    let mut s = ChunkStreamer::new_local(registry(), source, config).unwrap();
    assert!(s.pool.is_local(), "jobs run on the updating thread");
    let mut truth = Truth::new(true);
    let mut sink = Holder::default();
    let route = [
        ChunkPos::new(0, 0, 0),
        ChunkPos::new(2, 0, 1),
        ChunkPos::new(9, 1, -3),
        ChunkPos::new(0, 0, 0),
    ];
    let mut failed = HashSet::new();
    for (i, &c) in route.iter().enumerate() {
        let eye = eye_in(c);
        let idle = run_to_idle(&mut s, eye, &mut sink, &mut failed, 10_000);
        assert!(idle.is_some(), "stop {i}: not idle: {s:?}");
        check_against_truth(&s, &sink, &truth, eye, &failed, &format!("stop {i}"));
        // An edit in the eye's chunk and one at the view-distance edge.
        for at in [
            WorldPos::new(c.x * 32 + 3, c.y * 32 + 4, c.z * 32 + 31),
            WorldPos::new((c.x + 3) * 32, c.y * 32 + 1, c.z * 32 + 5),
        ] {
            if s.set_block(at, blocks::GLASS).is_ok() {
                truth.edit(at, blocks::GLASS);
            }
        }
        let idle = run_to_idle(&mut s, eye, &mut sink, &mut failed, 10_000);
        assert!(idle.is_some(), "stop {i} edited: not idle: {s:?}");
        check_against_truth(&s, &sink, &truth, eye, &failed, &format!("stop {i} edited"));
    }
    assert!(sink.held.len() > 20, "{} chunks drawn", sink.held.len());
}

/// A local streamer's update works within its budget: with a source that takes at
/// least 2 ms a chunk and a 5 ms budget, at most 3 chunks are made per update (the third
/// crosses it); with no budget, exactly one job per update, so streaming still moves on.
#[test]
fn a_local_update_stays_within_its_budget() {
    for (budget_ms, most) in [(5, 3), (0, 1)] {
        let calls = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let config = StreamConfig {
            view_distance: 2,
            vertical_distance: 0,
            local_budget: std::time::Duration::from_millis(budget_ms),
            ..StreamConfig::default()
        };
        let mut s = ChunkStreamer::new_local(registry(), Slow(calls.clone()), config).unwrap();
        let mut sink = Holder::default();
        let eye = DVec3::splat(16.0);
        let mut updates = 0;
        while !s.is_idle() {
            let before = calls.load(Ordering::SeqCst);
            s.update(eye, &mut sink).unwrap();
            let made = calls.load(Ordering::SeqCst) - before;
            assert!(
                made <= most,
                "budget {budget_ms} ms: {made} chunks in one update"
            );
            updates += 1;
            assert!(updates < 10_000, "not idle: {s:?}");
        }
        // Every chunk within the distance and its neighbours: 13 positions (a circle of
        // radius 2) and the rings around them, each made once.
        let made = calls.load(Ordering::SeqCst);
        assert!(made >= 13 * 3, "{made} chunks made");
        assert!(updates >= made / most, "{made} chunks in {updates} updates");
    }
}

/// The light tests' registry: the default blocks (the test source's ids) and the light
/// sources.
fn lit_registry() -> Arc<BlockRegistry> {
    Arc::new(BlockRegistry::with_lights())
}

/// The contract with light on (or off), once idle: every drawn chunk holds the meshes
/// [`Mesher::mesh_lit`] makes of the true world with the light [`LightField::new`] gives
/// the resident chunks (their true blocks, air ones included), with its corner light
/// (without light, those of [`Mesher::mesh`]);
/// every chunk within the view distance whose lit mesh has faces is drawn. Returns how
/// many corner lights of the drawn chunks are neither the open sky's full light nor dark
/// (block light, or sky light filtered or fallen off): what shows the light is not
/// trivial.
fn check_lit_against_truth(
    s: &ChunkStreamer,
    sink: &Holder,
    truth: &Truth,
    eye: DVec3,
    what: &str,
) -> usize {
    use voxel_core::{LightField, World};
    let mut world = World::new(lit_registry());
    for p in s.resident() {
        world.insert_chunk(p, truth.cached(p)).unwrap();
    }
    let field = LightField::new(&world);
    let mut mesher = Mesher::new(world.registry());
    let lit = s.has_light();
    let mut fresh = |pos: ChunkPos| match world.chunk(pos) {
        Some(c) if lit => mesher
            .mesh_lit(c, world.neighbourhood(pos), &field, pos)
            .unwrap(),
        Some(c) => mesher.mesh(c, world.neighbourhood(pos)).unwrap(),
        None => ChunkMeshes::default(),
    };
    let mut shaded = 0;
    for (&pos, meshes) in &sink.held {
        let want = fresh(pos);
        if !same_lit_meshes(meshes, &want) {
            // Which of the 27 chunks' light differs from the fresh field's.
            let differ: Vec<ChunkPos> = Neighbourhood::OFFSETS
                .iter()
                .chain([&[0, 0, 0]])
                .filter_map(|&d| pos.offset(d))
                .filter(|&p| {
                    let (a, b) = (s.light_chunk(p), field.chunk(p));
                    let cells = |c: Option<&voxel_core::LightChunk>| {
                        c.map(|c| {
                            (0..CHUNK_SIZE.pow(3))
                                .map(|i| c.get(i / 1024, i / 32 % 32, i % 32))
                                .collect::<Vec<_>>()
                        })
                    };
                    cells(a.as_deref()) != cells(b)
                })
                .collect();
            panic!(
                "{what}: {pos:?} drawn with {} quads and {} light bytes, a fresh lit mesh of \
                 the resident world has {} and {}; the light of {differ:?} differs from the \
                 fresh field's",
                meshes.len(),
                meshes.light.bytes(),
                want.len(),
                want.light.bytes(),
            );
        }
        assert_eq!(meshes.light.is_empty(), !lit, "{what}: {pos:?} lit: {lit}");
        shaded += meshes
            .light
            .palette
            .iter()
            .map(|p| p.unpack())
            .filter(|l| l.block != [0; 3] || (l.sky != [255; 3] && l.sky != [0; 3]))
            .count();
    }
    let centre = ChunkStreamer::centre_of(eye).unwrap();
    for o in &s.offsets {
        let pos = ChunkPos::new(centre.x + o[0], centre.y + o[1], centre.z + o[2]);
        if !sink.held.contains_key(&pos) {
            assert!(
                fresh(pos).is_empty(),
                "{what}: {pos:?} within the view distance not drawn"
            );
        }
    }
    shaded
}

/// Whether `a` and `b` hold the same quads, each with the same corner lights, in any
/// order: the mesher lists the quads of each block type, and the lights of its palette,
/// in the order it meets them, which follows the order of the chunk's palette (a chunk
/// generated again with its edits lists its types in another order than one edited in
/// place).
fn same_lit_meshes(a: &ChunkMeshes, b: &ChunkMeshes) -> bool {
    type Lit = (u32, u32, Option<[([u8; 3], [u8; 3]); 4]>);
    let kinds = |m: &ChunkMeshes| -> [Vec<Lit>; 3] {
        let l = &m.light;
        let kind = |quads: &[voxel_mesh::PackedQuad], lights: &[voxel_mesh::QuadLight]| {
            let mut v: Vec<Lit> = quads
                .iter()
                .enumerate()
                .map(|(i, q)| {
                    let c = lights.get(i).and_then(|ql| l.corners(*ql));
                    (q.geometry, q.block, c.map(|c| c.map(|c| (c.sky, c.block))))
                })
                .collect();
            v.sort_unstable();
            v
        };
        [
            kind(&m.opaque, &l.opaque),
            kind(&m.cutout, &l.cutout),
            kind(&m.translucent, &l.translucent),
        ]
    };
    let counts = |m: &ChunkMeshes| {
        [
            m.light.opaque.len(),
            m.light.cutout.len(),
            m.light.translucent.len(),
        ]
    };
    counts(a) == counts(b) && kinds(a) == kinds(b)
}

/// [`run_to_idle`] for a lit streamer: its light job lights some hundred chunks at first
/// (a second or more where other tests share the cores), so the updates wait longer
/// between them; fails past two minutes (a streamer that never becomes idle).
fn run_lit_to_idle(
    s: &mut ChunkStreamer,
    eye: DVec3,
    sink: &mut Holder,
    failed: &mut HashSet<ChunkPos>,
) -> Option<usize> {
    let start = std::time::Instant::now();
    for i in 0.. {
        let f = s.update(eye, sink).unwrap();
        failed.extend(f.failed.iter().map(|x| x.0));
        if s.is_idle() {
            return Some(i);
        }
        if start.elapsed() > std::time::Duration::from_secs(120) {
            return None;
        }
        if s.jobs() > 0 {
            std::thread::sleep(std::time::Duration::from_micros(300));
        }
    }
    None
}

/// A streamer with light over the deterministic test source with the light registry.
fn lit_streamer(view_distance: u32, local: bool) -> ChunkStreamer {
    let config = StreamConfig {
        view_distance,
        vertical_distance: 1,
        hysteresis: 1,
        threads: 2,
        local_budget: std::time::Duration::from_millis(2),
        ..StreamConfig::default()
    };
    let source = TestSource {
        failing: true,
        changing: None,
    };
    let s = if local {
        ChunkStreamer::new_local(lit_registry(), source, config)
    } else {
        ChunkStreamer::new(lit_registry(), source, config)
    };
    s.unwrap().with_light()
}

/// Light as chunks stream: a route of stops, moves two chunks and a teleport, with edits
/// that light (a torch, lava), filter (red glass) and stop light (stone over a shaft),
/// in the eye's chunk, on chunk borders and at the view-distance edge; each stop checked
/// once idle against the resident world's light. Then light off (the unlit contract) and
/// on again (the lit one), on worker threads and on the updating thread.
#[test]
fn a_lit_streamer_holds_the_lit_truth_once_idle() {
    use voxel_core::light_blocks::{LAVA, TORCH};
    for local in [false, true] {
        let mut s = lit_streamer(2, local);
        let mut truth = Truth::new(true);
        let mut sink = Holder::default();
        let mut failed = HashSet::new();
        let mut shaded = 0;
        let route = [
            ChunkPos::new(0, 0, 0),
            ChunkPos::new(-2, 0, 0),
            ChunkPos::new(7, 1, -3),
            ChunkPos::new(0, 0, 0),
        ];
        for (i, &c) in route.iter().enumerate() {
            let eye = eye_in(c);
            let what = format!("local {local}, stop {i}");
            let idle = run_lit_to_idle(&mut s, eye, &mut sink, &mut failed);
            assert!(idle.is_some(), "{what}: not idle: {s:?}");
            shaded += check_lit_against_truth(&s, &sink, &truth, eye, &what);
            let (x, y, z) = (c.x * 32, c.y * 32, c.z * 32);
            for (at, id) in [
                (WorldPos::new(x + 5, y + 6, z + 7), TORCH),
                (WorldPos::new(x + 31, y + 2, z + 16), LAVA),
                (WorldPos::new(x + 32, y + 2, z + 16), blocks::RED_GLASS),
                (WorldPos::new(x + 16, y + 31, z + 16), blocks::STONE),
                (WorldPos::new(x + 64, y + 5, z), TORCH),
                (WorldPos::new(x + 5, y + 6, z + 7), blocks::GLASS),
            ] {
                if s.set_block(at, id).is_ok() {
                    truth.edit(at, id);
                }
            }
            let idle = run_lit_to_idle(&mut s, eye, &mut sink, &mut failed);
            assert!(idle.is_some(), "{what} edited: not idle: {s:?}");
            shaded += check_lit_against_truth(&s, &sink, &truth, eye, &format!("{what} edited"));
        }
        assert!(
            shaded > 100,
            "local {local}: {shaded} corner lights other than the open sky's"
        );
        let eye = eye_in(route[3]);
        s.set_light(false);
        let idle = run_lit_to_idle(&mut s, eye, &mut sink, &mut failed);
        assert!(idle.is_some(), "light off: not idle");
        check_lit_against_truth(&s, &sink, &truth, eye, "light off");
        s.set_light(true);
        let idle = run_lit_to_idle(&mut s, eye, &mut sink, &mut failed);
        assert!(idle.is_some(), "light on again: not idle");
        check_lit_against_truth(&s, &sink, &truth, eye, "light on again");
        assert!(s.light_bytes() > 0);
        assert!(sink.held.len() > 10, "{} chunks drawn", sink.held.len());
    }
}
