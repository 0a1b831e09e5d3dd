//! The README's setup, run as a fresh machine would: `bash scripts/test.sh --setup-only` (the
//! same ensure-* steps `.ci/run` and `scripts/run.sh` take) with a PATH that has no
//! wasm-bindgen, Chromium, Xvfb or wasm32 target, no Vulkan or GL driver (the file probes look
//! under an empty `SETUP_ROOT`), and the installers (`apt-get`, `rustup`, `cargo`) replaced by
//! stubs that record their arguments and then make the tool they were asked for appear. Each
//! missing tool must be installed, the script must reach its end, a second run must install
//! nothing, and a step that cannot run (not root) or whose installer fails must say which step
//! and what to run by hand.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Real tools the scripts use besides the installers; linked into the fake PATH.
const REAL_TOOLS: &[&str] = &[
    "bash", "sh", "awk", "grep", "cat", "dirname", "mkdir", "chmod", "touch", "env", "sed", "cut",
    "tr", "head",
];

/// The installer stubs. `$FAKE` is the fake machine's folder: `bin/` (on PATH), `root/`
/// (`SETUP_ROOT`), `log` (one line per installer call), `libs` (what `ldconfig -p` lists),
/// `toolchains` and `targets` (rustup's state).
const STUBS: &[(&str, &str)] = &[
    (
        "apt-get",
        r#"echo "apt-get $*" >> "$FAKE/log"
[ -n "${FAIL_APT:-}" ] && exit 100
[ "$1" = update ] && exit 0
for pkg in "$@"; do
    case "$pkg" in
        mesa-vulkan-drivers) mkdir -p "$FAKE/root/usr/share/vulkan/icd.d" && touch "$FAKE/root/usr/share/vulkan/icd.d/lvp_icd.json" ;;
        libgl1-mesa-dri) mkdir -p "$FAKE/root/usr/lib/x86_64-linux-gnu/dri" && touch "$FAKE/root/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so" ;;
        libegl1) echo "libEGL.so.1" >> "$FAKE/libs" ;;
        libegl-mesa0) echo "libEGL_mesa.so.0" >> "$FAKE/libs" ;;
        libgles2) echo "libGLESv2.so.2" >> "$FAKE/libs" ;;
        libxkbcommon-x11-0) echo "libxkbcommon-x11.so.0" >> "$FAKE/libs" ;;
        xvfb) printf '#!/bin/sh\nexit 0\n' > "$FAKE/bin/Xvfb" && chmod +x "$FAKE/bin/Xvfb" ;;
        chromium) printf '#!/bin/sh\nexit 0\n' > "$FAKE/bin/chromium" && chmod +x "$FAKE/bin/chromium" ;;
    esac
done"#,
    ),
    ("ldconfig", r#"cat "$FAKE/libs""#),
    ("id", r#"echo "${FAKE_UID:-0}""#),
    (
        "rustup",
        r#"echo "rustup $*" >> "$FAKE/log"
case "$1 $2" in
    "toolchain list") cat "$FAKE/toolchains" ;;
    "toolchain install") echo "1.97.1-x86_64-unknown-linux-gnu" >> "$FAKE/toolchains" ;;
    "target list") cat "$FAKE/targets" ;;
    "target add") echo "$3" >> "$FAKE/targets" ;;
    *) exit 1 ;;
esac"#,
    ),
    (
        "cargo",
        r#"echo "cargo $*" >> "$FAKE/log"
[ -n "${FAIL_CARGO:-}" ] && exit 101
# cargo's own record says the CLI is installed: it succeeds and installs nothing.
[ -n "${CARGO_NOOP:-}" ] && exit 0
if [ "$1" = install ]; then
    for a in "$@"; do case "$a" in =*) version="${a#=}" ;; esac; done
    printf '#!/bin/sh\necho "wasm-bindgen %s"\n' "$version" > "$FAKE/bin/wasm-bindgen"
    chmod +x "$FAKE/bin/wasm-bindgen"
fi"#,
    ),
];

struct FakeMachine {
    dir: PathBuf,
}

impl FakeMachine {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("voxel-setup-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(dir.join("bin")).expect("a temp folder");
        fs::create_dir_all(dir.join("root")).expect("the fake machine's files");
        for file in ["log", "libs", "toolchains"] {
            fs::write(dir.join(file), "").expect("the fake machine's files");
        }
        // rustup lists the host target only: no wasm32 yet.
        fs::write(dir.join("targets"), "x86_64-unknown-linux-gnu\n")
            .expect("the fake machine's files");
        for tool in REAL_TOOLS {
            let real =
                which(tool).unwrap_or_else(|| panic!("the setup test needs `{tool}` on PATH"));
            std::os::unix::fs::symlink(real, dir.join("bin").join(tool))
                .expect("the fake machine's files");
        }
        for (name, body) in STUBS {
            let path = dir.join("bin").join(name);
            fs::write(&path, format!("#!/bin/bash\n{body}\n")).expect("the fake machine's files");
            use std::os::unix::fs::PermissionsExt;
            fs::set_permissions(&path, fs::Permissions::from_mode(0o755))
                .expect("the fake machine's files");
        }
        Self { dir }
    }

    /// `bash scripts/test.sh --setup-only` on this fake machine, with extra environment.
    fn setup(&self, env: &[(&str, &str)]) -> Output {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut command = Command::new(self.dir.join("bin/bash"));
        command
            .arg(repo.join("scripts/test.sh"))
            .arg("--setup-only")
            .env_clear()
            .env("PATH", self.dir.join("bin"))
            .env("HOME", &self.dir)
            .env("TMPDIR", &self.dir)
            .env("FAKE", &self.dir)
            .env("SETUP_ROOT", self.dir.join("root"));
        for (key, value) in env {
            command.env(key, value);
        }
        command.output().expect("bash runs")
    }

    fn log(&self) -> String {
        fs::read_to_string(self.dir.join("log")).expect("the fake machine's files")
    }

    fn clear_log(&self) {
        fs::write(self.dir.join("log"), "").expect("the fake machine's files");
    }
}

impl Drop for FakeMachine {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.dir);
    }
}

fn which(tool: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(tool))
        .find(|candidate| candidate.is_file())
}

fn locked_wasm_bindgen() -> String {
    let lock = fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../Cargo.lock"))
        .expect("the fake machine's files");
    let at = lock
        .find("name = \"wasm-bindgen\"\nversion = \"")
        .expect("wasm-bindgen in Cargo.lock");
    let rest = &lock[at + "name = \"wasm-bindgen\"\nversion = \"".len()..];
    rest[..rest.find('"').expect("the fake machine's files")].to_string()
}

fn report(output: &Output, log: &str) -> String {
    format!(
        "status {:?}\nstderr:\n{}\nstdout:\n{}\ninstaller calls:\n{log}",
        output.status.code(),
        String::from_utf8_lossy(&output.stderr),
        String::from_utf8_lossy(&output.stdout)
    )
}

#[test]
fn a_fresh_machine_gets_every_missing_tool_and_the_script_reaches_its_end() {
    let machine = FakeMachine::new("fresh");
    let output = machine.setup(&[]);
    let log = machine.log();
    let text = report(&output, &log);
    assert!(output.status.success(), "setup stopped early:\n{text}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("setup complete"), "{text}");
    let expected = [
        "rustup toolchain install".to_string(),
        "apt-get update -qq".to_string(),
        "apt-get install -y -qq --no-install-recommends mesa-vulkan-drivers libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri xvfb libxkbcommon-x11-0".to_string(),
        "apt-get install -y -qq --no-install-recommends chromium".to_string(),
        "rustup target add wasm32-unknown-unknown".to_string(),
        format!("cargo install --quiet --force wasm-bindgen-cli --version ={}", locked_wasm_bindgen()),
    ];
    for call in &expected {
        assert!(log.lines().any(|line| line == call), "no `{call}`:\n{text}");
    }
    // Each install is announced, not silent.
    for what in [
        "Rust 1.97.1",
        "mesa-vulkan-drivers",
        "chromium",
        "wasm32-unknown-unknown",
        "wasm-bindgen-cli",
    ] {
        assert!(
            stderr
                .lines()
                .any(|line| line.starts_with("installing") && line.contains(what)),
            "installing {what} is not announced:\n{text}"
        );
    }
    // The installed tools are found afterwards: a second run installs nothing.
    machine.clear_log();
    let again = machine.setup(&[]);
    let log = machine.log();
    assert!(again.status.success(), "{}", report(&again, &log));
    let installs: Vec<&str> = log
        .lines()
        .filter(|line| line.contains("install") && !line.contains("--installed"))
        .collect();
    assert!(
        installs
            .iter()
            .all(|line| *line == "rustup toolchain install"),
        "a set-up machine installs again: {installs:?}"
    );
}

#[test]
fn without_root_the_step_names_the_packages_and_the_command_to_run() {
    let machine = FakeMachine::new("user");
    let output = machine.setup(&[("FAKE_UID", "1000")]);
    let log = machine.log();
    let text = report(&output, &log);
    assert!(!output.status.success(), "{text}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("sudo apt-get install -y mesa-vulkan-drivers libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri xvfb"),
        "{text}"
    );
    assert!(
        !log.contains("apt-get"),
        "apt-get ran without root:\n{text}"
    );
}

#[test]
fn a_failing_installer_names_its_step_and_what_to_run_by_hand() {
    let machine = FakeMachine::new("apt-fails");
    let output = machine.setup(&[("FAIL_APT", "1")]);
    let text = report(&output, &machine.log());
    assert!(!output.status.success(), "{text}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("setup step 'Vulkan/GL drivers' failed"),
        "{text}"
    );
    assert!(
        stderr.contains(
            "run it by hand: sudo apt-get update && sudo apt-get install -y mesa-vulkan-drivers"
        ),
        "{text}"
    );

    let machine = FakeMachine::new("cargo-fails");
    let output = machine.setup(&[("FAIL_CARGO", "1")]);
    let text = report(&output, &machine.log());
    assert!(!output.status.success(), "{text}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("setup step 'wasm-bindgen' failed"),
        "{text}"
    );
    assert!(
        stderr.contains(&format!(
            "run it by hand: cargo install --force wasm-bindgen-cli --version ={}",
            locked_wasm_bindgen()
        )),
        "{text}"
    );
}

/// An install that succeeds but leaves no `wasm-bindgen` on the PATH (cargo's record said
/// it was installed, or cargo's bin folder is not on the PATH) is an error naming the step,
/// not a setup that reports success and fails later in the browser test.
#[test]
fn an_install_that_leaves_no_tool_on_the_path_is_an_error() {
    let machine = FakeMachine::new("cargo-noop");
    let output = machine.setup(&[("CARGO_NOOP", "1")]);
    let text = report(&output, &machine.log());
    assert!(!output.status.success(), "{text}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("setup step 'wasm-bindgen' installed wasm-bindgen-cli")
            && stderr.contains("on the PATH is none"),
        "{text}"
    );
}
