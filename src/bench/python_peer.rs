//! The Python side of `drapekit bench peer`: a virtual environment with pinned versions of
//! NVIDIA Warp and Newton, created on first use, and the driver script (`peer.py`, shipped
//! inside the binary) that times their solvers and prints one `PEER {json}` line per point.

use crate::atomic_file::write_atomic;
use crate::error::{Error, InputError};
use serde::Deserialize;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The packages the peers run on, pinned so that a later benchmark change cannot slip in.
pub const PINNED: [(&str, &str); 3] = [
    ("warp-lang", "1.19.0"),
    ("newton", "1.8.0"),
    ("numpy", "2.4.6"),
];

/// Newton needs Python 3.10 or newer.
const MIN_PYTHON: (u32, u32) = (3, 10);

const DRIVER: &str = include_str!("peer.py");
const DRIVER_NAME: &str = "drapekit_peer.py";

/// A ready environment: its interpreter and what it runs.
#[derive(Clone, Debug)]
pub struct PythonEnv {
    /// The virtual environment's folder.
    pub venv: PathBuf,
    /// Its interpreter.
    pub python: PathBuf,
    /// Versions of Python, numpy, warp and newton, as the driver reports them.
    pub versions: Versions,
}

/// What `peer.py versions` prints.
#[derive(Clone, Debug, Default, Deserialize)]
pub struct Versions {
    /// Python.
    pub python: String,
    /// numpy.
    pub numpy: String,
    /// warp-lang (or "missing: …").
    pub warp: String,
    /// newton (or "missing: …").
    pub newton: String,
}

/// One measured point from the driver.
#[derive(Clone, Debug, Deserialize)]
pub struct PeerRecord {
    /// "warp" or "newton".
    pub system: String,
    /// "symplectic" or "implicit".
    pub integrator: String,
    /// Newton's solver class, if Newton.
    #[serde(default)]
    pub solver: Option<String>,
    /// Grid side.
    pub grid: u32,
    /// Particles of the peer's cloth.
    pub particles: usize,
    /// Springs of the peer's cloth.
    pub springs: usize,
    /// Sum of the rest lengths in m (f64).
    pub rest_length_sum: f64,
    /// Pinned particles.
    pub pinned: usize,
    /// Particle mass in kg.
    pub mass: f64,
    /// Grid spacing in m.
    pub spacing: f64,
    /// The distinct spring stiffnesses in N/m.
    pub stiffness: Vec<f64>,
    /// The distinct spring dampings in N·s/m.
    pub damping: Vec<f64>,
    /// The benchmark's frames per second.
    pub fps: f64,
    /// The benchmark's substeps per frame.
    pub benchmark_substeps: u32,
    /// Substeps per frame of this run (Newton; Warp's are `benchmark_substeps`).
    #[serde(default)]
    pub substeps: Option<u32>,
    /// Implicit sweeps per substep (0 for symplectic).
    pub iterations: u32,
    /// Timed frames.
    pub frames: u32,
    /// Median seconds per frame.
    pub median_frame_seconds: f64,
    /// Little-endian f32 xyz positions after the last frame.
    pub state: PathBuf,
    /// Warp's device the point ran on ("cpu", "cuda:0").
    #[serde(default)]
    pub device: Option<String>,
    /// That device's name as Warp reports it (the GPU's name for CUDA).
    #[serde(default)]
    pub device_name: Option<String>,
}

impl PeerRecord {
    /// Substeps per frame this point ran.
    pub fn substeps_per_frame(&self) -> u32 {
        self.substeps.unwrap_or(self.benchmark_substeps)
    }

    /// Whether the point ran on a CUDA device.
    pub fn on_cuda(&self) -> bool {
        self.device
            .as_deref()
            .is_some_and(|d| d.starts_with("cuda"))
    }

    /// The device in words, e.g. "Warp's cuda:0 (NVIDIA H100 80GB HBM3)".
    pub fn device_description(&self) -> String {
        match (&self.device, &self.device_name) {
            (Some(d), _) if d == "cpu" => "Warp's CPU device".into(),
            (Some(d), Some(n)) if n != d => format!("Warp's {d} ({n})"),
            (Some(d), _) => format!("Warp's {d}"),
            _ => "Warp's CPU device".into(),
        }
    }
}

fn pip_command(python: &Path) -> String {
    let pins: Vec<String> = PINNED.iter().map(|(p, v)| format!("{p}=={v}")).collect();
    format!("{} -m pip install {}", python.display(), pins.join(" "))
}

fn setup_error(path: &Path, problem: String, fix: String) -> Error {
    Error::Input(InputError::new(path, "bench peer", problem, fix))
}

fn tail(bytes: &[u8], lines: usize) -> String {
    let text = String::from_utf8_lossy(bytes);
    let all: Vec<&str> = text.lines().collect();
    all[all.len().saturating_sub(lines)..].join("\n")
}

/// The venv's interpreter path.
fn venv_python(venv: &Path) -> PathBuf {
    if cfg!(windows) {
        venv.join("Scripts").join("python.exe")
    } else {
        venv.join("bin").join("python")
    }
}

/// Checks that `python` runs and is new enough.
fn check_python(python: &str) -> Result<(), Error> {
    let path = Path::new(python);
    let fix = format!(
        "install Python {}.{} or newer with its venv module (Debian/Ubuntu: apt-get install \
         python3 python3-venv), or pass --python /path/to/python3; to time drapekit alone, \
         use --systems drapekit",
        MIN_PYTHON.0, MIN_PYTHON.1
    );
    let out = Command::new(python)
        .args(["-c", "import sys; print('%d.%d' % sys.version_info[:2])"])
        .output()
        .map_err(|e| setup_error(path, format!("cannot run Python ({e})"), fix.clone()))?;
    let version = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let parsed: Option<(u32, u32)> = version
        .split_once('.')
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)));
    match parsed {
        Some(v) if out.status.success() && v >= MIN_PYTHON => Ok(()),
        _ => Err(setup_error(
            path,
            format!(
                "needs Python {}.{} or newer, found {:?}",
                MIN_PYTHON.0,
                MIN_PYTHON.1,
                if version.is_empty() {
                    tail(&out.stderr, 3)
                } else {
                    version
                }
            ),
            fix,
        )),
    }
}

/// Reads the versions the environment holds.
fn versions(python: &Path, driver: &Path) -> Result<Versions, Error> {
    let records = run_driver_raw(python, driver, &["versions".to_string()])?;
    let first = records.into_iter().next().ok_or_else(|| {
        setup_error(
            driver,
            "the driver printed no versions".into(),
            "remove the environment folder and run the command again".into(),
        )
    })?;
    serde_json::from_value(first).map_err(|e| {
        setup_error(
            driver,
            format!("unreadable versions: {e}"),
            "remove the environment folder and run the command again".into(),
        )
    })
}

/// Whether every pinned package is installed at its pinned version.
fn pinned_installed(v: &Versions) -> bool {
    let want = |name: &str| PINNED.iter().find(|(p, _)| *p == name).map(|(_, v)| *v);
    Some(v.warp.as_str()) == want("warp-lang")
        && Some(v.newton.as_str()) == want("newton")
        && Some(v.numpy.as_str()) == want("numpy")
}

/// Uses `python` as it is, with the warp and newton it imports (e.g. from PYTHONPATH, on a
/// machine without the network), whatever their versions: the report records them. The driver
/// is written into `dir`.
pub fn use_python(python: &str, dir: &Path) -> Result<PythonEnv, Error> {
    check_python(python)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let driver = dir.join(DRIVER_NAME);
    write_atomic(&driver, DRIVER.as_bytes())?;
    let found = versions(Path::new(python), &driver)?;
    if found.warp.starts_with("missing") || found.newton.starts_with("missing") {
        return Err(setup_error(
            Path::new(python),
            format!(
                "--no-venv: {python} cannot import warp and newton (warp {}, newton {})",
                found.warp, found.newton
            ),
            format!(
                "install them for that Python or put them on PYTHONPATH, or leave out \
                 --no-venv to create the pinned environment ({})",
                pip_command(Path::new(python))
            ),
        ));
    }
    Ok(PythonEnv {
        venv: dir.to_path_buf(),
        python: PathBuf::from(python),
        versions: found,
    })
}

/// Creates (on first use) the environment in `venv` with `python`, installs the pinned
/// packages if they are not there, and writes the driver into it.
pub fn ensure_env(python: &str, venv: &Path) -> Result<PythonEnv, Error> {
    let interpreter = venv_python(venv);
    if !interpreter.exists() {
        check_python(python)?;
        eprintln!(
            "drapekit: creating the Python environment {} (once)",
            venv.display()
        );
        let out = Command::new(python)
            .arg("-m")
            .arg("venv")
            .arg(venv)
            .output()
            .map_err(|e| Error::io(Path::new(python), e))?;
        if !out.status.success() {
            return Err(setup_error(
                venv,
                format!("`{python} -m venv` failed:\n{}", tail(&out.stderr, 6)),
                format!(
                    "install Python's venv module (Debian/Ubuntu: apt-get install python3-venv), \
                     or create the environment yourself: {python} -m venv {} && {}",
                    venv.display(),
                    pip_command(&interpreter)
                ),
            ));
        }
    }
    let driver = venv.join(DRIVER_NAME);
    write_atomic(&driver, DRIVER.as_bytes())?;
    let found = versions(&interpreter, &driver)?;
    if pinned_installed(&found) {
        return Ok(PythonEnv {
            venv: venv.to_path_buf(),
            python: interpreter,
            versions: found,
        });
    }
    let pins: Vec<String> = PINNED.iter().map(|(p, v)| format!("{p}=={v}")).collect();
    eprintln!(
        "drapekit: installing {} into {} (about a minute, once)",
        pins.join(" "),
        venv.display()
    );
    let out = Command::new(&interpreter)
        .args(["-m", "pip", "install", "--disable-pip-version-check", "-q"])
        .args(&pins)
        .output()
        .map_err(|e| Error::io(&interpreter, e))?;
    let found = versions(&interpreter, &driver)?;
    if !out.status.success() || !pinned_installed(&found) {
        return Err(setup_error(
            venv,
            format!(
                "installing the pinned packages failed (found warp {}, newton {}, numpy {}):\n{}",
                found.warp,
                found.newton,
                found.numpy,
                tail(&out.stderr, 8)
            ),
            format!(
                "check the network (pip needs the package index), then run: {}",
                pip_command(&interpreter)
            ),
        ));
    }
    Ok(PythonEnv {
        venv: venv.to_path_buf(),
        python: interpreter,
        versions: found,
    })
}

/// Runs the driver with `args`; its stderr and non-`PEER` stdout lines go to our stderr.
fn run_driver_raw(
    python: &Path,
    driver: &Path,
    args: &[String],
) -> Result<Vec<serde_json::Value>, Error> {
    let mut child = Command::new(python)
        .arg(driver)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(|e| Error::io(python, e))?;
    let mut records = Vec::new();
    let stdout = child.stdout.take().expect("piped stdout");
    for line in BufReader::new(stdout).lines() {
        let line = line.map_err(|e| Error::io(driver, e))?;
        match line.strip_prefix("PEER ") {
            Some(json) => records.push(serde_json::from_str(json).map_err(|e| {
                setup_error(
                    driver,
                    format!("unreadable driver output: {e}"),
                    String::new(),
                )
            })?),
            None => eprintln!("{line}"),
        }
    }
    let status = child.wait().map_err(|e| Error::io(python, e))?;
    if !status.success() {
        return Err(setup_error(
            driver,
            format!(
                "`{} {} {}` failed ({status}); its error is printed above",
                python.display(),
                driver.display(),
                args.join(" ")
            ),
            "read the Python error above; remove the environment folder to reinstall it".into(),
        ));
    }
    Ok(records)
}

/// Runs one driver command (`warp …` or `newton …`) and returns its points.
pub fn run_driver(env: &PythonEnv, args: &[String]) -> Result<Vec<PeerRecord>, Error> {
    let driver = env.venv.join(DRIVER_NAME);
    run_driver_raw(&env.python, &driver, args)?
        .into_iter()
        .map(|v| {
            serde_json::from_value(v).map_err(|e| {
                setup_error(
                    &driver,
                    format!("unreadable driver output: {e}"),
                    "remove the environment folder and run the command again".into(),
                )
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::PeerRecord;

    fn record(device: &str) -> PeerRecord {
        let json = format!(
            r#"{{"system": "newton", "integrator": "implicit", "solver": "SolverVBD", "grid": 8,
            "particles": 64, "springs": 306, "rest_length_sum": 1.0, "pinned": 2, "mass": 0.1,
            "spacing": 0.1, "stiffness": [1000.0], "damping": [10.0], "fps": 60.0,
            "benchmark_substeps": 16, "substeps": 10, "iterations": 10, "frames": 2,
            "median_frame_seconds": 0.01, "state": "s.f32"{device}}}"#
        );
        serde_json::from_str(&json).unwrap()
    }

    #[test]
    fn a_record_names_its_device_and_whether_it_is_cuda() {
        let cuda = record(r#", "device": "cuda:0", "device_name": "NVIDIA H200""#);
        assert!(cuda.on_cuda());
        assert_eq!(cuda.device_description(), "Warp's cuda:0 (NVIDIA H200)");
        let cpu = record(r#", "device": "cpu", "device_name": "cpu""#);
        assert!(!cpu.on_cuda());
        assert_eq!(cpu.device_description(), "Warp's CPU device");
        // A driver from before the device field ran on the CPU.
        let old = record("");
        assert!(!old.on_cuda());
        assert_eq!(old.device_description(), "Warp's CPU device");
    }
}
