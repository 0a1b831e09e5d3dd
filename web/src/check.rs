//! What the page reports in its test mode (`?test=1`), to the server that served it, and
//! how: the test (`tests/browser.rs`) reads it with the same functions.
//!
//! For each technique of [`voxel_render::Technique::ALL`] the page posts one report to
//! [`report_path`]: the picture it drew at [`TEST_SIZE`] after [`TEST_FRAMES`] frames
//! (RGBA8, sRGB, rows top down), or the renderer's refusal (`Error::Unsupported`), or
//! another error. Then it posts its summary to `/done`; a panic is posted to `/panic`,
//! a logged error or a GPU error wgpu did not return to `/log`.

use voxel_render::Technique;

/// The size every technique is drawn at: small, for a CPU GPU (SwiftShader, lavapipe).
pub const TEST_SIZE: (u32, u32) = (160, 90);
/// Frames drawn before the picture is read (the first sorts and fits; the second draws
/// what a game's next frame shows).
pub const TEST_FRAMES: u32 = 2;
/// Chunks of terrain each way the test's scene loads (5 × 2 × 5 chunks).
pub const TEST_RADIUS: i32 = 2;
/// The seed of the test's scene.
pub const TEST_SEED: u32 = 1;
/// Whether the test's scene is drawn with its light field (as the page draws it by
/// default: `docs/light.md`).
pub const TEST_LIGHT: bool = true;

/// What became of a technique.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// It drew; the body is the picture.
    Drew,
    /// The renderer refused it with `Error::Unsupported`; the body is the message.
    Refused,
    /// Another error; the body is the message.
    Failed,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Drew => "drew",
            Kind::Refused => "refused",
            Kind::Failed => "failed",
        }
    }
}

/// One technique's report, as its path says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Report {
    /// The technique asked for.
    pub technique: Technique,
    /// What became of it.
    pub kind: Kind,
    /// The technique that drew (itself, or its replacement on this device).
    pub drew: Option<Technique>,
    /// Whether MBOIT's moments were 32-bit floats (the device blends them).
    pub single_precision_moments: bool,
}

/// The path a report is posted to.
pub fn report_path(report: &Report) -> String {
    let mut path = format!(
        "/technique/{}?kind={}&single={}",
        report.technique,
        report.kind.name(),
        u8::from(report.single_precision_moments)
    );
    if let Some(drew) = report.drew {
        path += &format!("&drew={drew}");
    }
    path
}

/// The report a path says, `None` when it is not one.
pub fn parse_report_path(path: &str) -> Option<Report> {
    let rest = path.strip_prefix("/technique/")?;
    let (name, query) = rest.split_once('?')?;
    let technique = name.parse::<Technique>().ok()?;
    let (mut kind, mut drew, mut single) = (None, None, false);
    for pair in query.split('&') {
        match pair.split_once('=')? {
            ("kind", k) => {
                kind = [Kind::Drew, Kind::Refused, Kind::Failed]
                    .into_iter()
                    .find(|x| x.name() == k);
            }
            ("drew", d) => drew = Some(d.parse::<Technique>().ok()?),
            ("single", s) => single = s == "1",
            _ => return None,
        }
    }
    Some(Report {
        technique,
        kind: kind?,
        drew,
        single_precision_moments: single,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_say_what_they_were_made_from() {
        let r = Report {
            technique: Technique::Reference,
            kind: Kind::Drew,
            drew: Some(Technique::PeelReference),
            single_precision_moments: true,
        };
        let path = report_path(&r);
        assert_eq!(
            path,
            "/technique/reference?kind=drew&single=1&drew=peel-reference"
        );
        assert_eq!(parse_report_path(&path), Some(r));
        let refused = Report {
            technique: Technique::Mboit,
            kind: Kind::Refused,
            drew: None,
            single_precision_moments: false,
        };
        assert_eq!(parse_report_path(&report_path(&refused)), Some(refused));
        for bad in [
            "/technique/nope?kind=drew",
            "/technique/mboit?kind=maybe",
            "/technique/mboit",
            "/done",
        ] {
            assert_eq!(parse_report_path(bad), None, "{bad}");
        }
    }
}
