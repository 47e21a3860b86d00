//! With the `cuda` feature, compiles the `kernels` crate to PTX with the `nvptx64-nvidia-cuda`
//! target of the dated nightly toolchain that `kernels/nvptx-toolchain` names (the kernels call
//! NVPTX intrinsics by name, which a later nightly may rename) and leaves it in
//! `OUT_DIR/coil_kernels.ptx`, which `host/cuda/gpu.rs` embeds. A default build needs neither
//! nightly nor CUDA.
//!
//! Where it finds `ptxas` and `fatbinary` (`COIL_PTXAS`, then `PATH`, then pip's
//! `nvidia-cuda-nvcc`), it also compiles the PTX ahead of time into cubins for [`CUBIN_ARCHS`]
//! and packs them with the PTX into `OUT_DIR/coil_kernels.fatbin`, so that a run on those GPUs
//! starts without the driver JIT-compiling some 190 kernels; without them it embeds the PTX
//! alone and says so.
//!
//! `COIL_PTX_TARGET_CPU` picks the PTX target (default `sm_70`; the driver JIT-compiles it for
//! GPUs newer than the cubins).

use std::env;
use std::path::{Path, PathBuf};
use std::process::{exit, Command};

/// The nightly toolchain the kernels are compiled with, as `kernels/nvptx-toolchain` names it.
fn toolchain() -> &'static str {
    include_str!("kernels/nvptx-toolchain").trim()
}

/// The command that installs it.
fn install() -> String {
    format!("rustup toolchain install {} --profile minimal --component rust-src", toolchain())
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var_os("CARGO_FEATURE_CUDA").is_none() {
        return;
    }
    println!("cargo:rerun-if-changed=kernels");
    println!("cargo:rerun-if-env-changed=COIL_PTX_TARGET_CPU");
    println!("cargo:rerun-if-env-changed=COIL_PTXAS");
    let root = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let target_cpu = env::var("COIL_PTX_TARGET_CPU").unwrap_or_else(|_| "sm_70".into());
    require_nightly_with_rust_src();

    // A target folder of its own: the outer build holds the lock on `target/`.
    let target_dir = out.join("ptx-build");
    let mut cargo = Command::new("rustup");
    cargo
        .args(["run", toolchain(), "cargo", "rustc", "-p", "coil-kernels", "--profile", "ptx"])
        .args(["--target", "nvptx64-nvidia-cuda", "-Zbuild-std=core", "--crate-type", "cdylib"])
        .arg("--manifest-path")
        .arg(root.join("Cargo.toml"))
        .arg("--target-dir")
        .arg(&target_dir)
        .args(["--", "-C", &format!("target-cpu={target_cpu}"), "--emit=asm", "-C", "linker=true"]);
    // The outer cargo's settings for this build script would steer the nested one to the host
    // compiler and flags.
    for (key, _) in env::vars_os() {
        let key = key.to_string_lossy();
        let keep = key == "CARGO_HOME"
            || key.starts_with("CARGO_NET")
            || key.starts_with("CARGO_HTTP")
            || key.starts_with("CARGO_REGISTR");
        let steers = key.starts_with("CARGO_")
            || key.starts_with("RUSTC")
            || matches!(
                &*key,
                "RUSTFLAGS"
                    | "RUSTDOCFLAGS"
                    | "RUSTUP_TOOLCHAIN"
                    | "TARGET"
                    | "HOST"
                    | "PROFILE"
                    | "OUT_DIR"
                    | "OPT_LEVEL"
                    | "DEBUG"
                    | "NUM_JOBS"
            );
        if steers && !keep {
            cargo.env_remove(&*key);
        }
    }
    let status = cargo.status().unwrap_or_else(|e| fail(&format!("cannot start `rustup run {} cargo`: {e}", toolchain())));
    if !status.success() {
        fail("compiling the kernels to PTX failed (see the errors above)");
    }
    let ptx = target_dir.join("nvptx64-nvidia-cuda/ptx/deps/coil_kernels.s");
    copy(&ptx, &out.join("coil_kernels.ptx"));

    let fatbin = out.join("coil_kernels.fatbin");
    let archs = match cuda_tools() {
        Some(tools) => match compile_fatbin(&tools, &ptx, &fatbin, &target_cpu) {
            Ok(()) => CUBIN_ARCHS.iter().map(u32::to_string).collect::<Vec<_>>().join(","),
            Err(why) => fail(&why),
        },
        None => {
            println!(
                "cargo:warning=ptxas not found (set COIL_PTXAS, or `pip install nvidia-cuda-nvcc`): embedding the PTX alone, which the driver compiles at every start"
            );
            std::fs::write(&fatbin, []).unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", fatbin.display())));
            String::new()
        }
    };
    println!("cargo:rustc-env=COIL_CUBIN_ARCHS={archs}");
}

/// The GPU architectures compiled ahead of time: an sm_80 cubin runs on every sm_8x GPU (A100,
/// A10, L4, L40, the RTX 30 and 40 series), an sm_90 one on the H100 and H200. Others
/// JIT-compile the PTX the fatbin carries beside them.
const CUBIN_ARCHS: [u32; 2] = [80, 90];

/// `ptxas` and `fatbinary`, from the folder of the first `ptxas` found.
struct CudaTools {
    ptxas: PathBuf,
    fatbinary: PathBuf,
}

fn cuda_tools() -> Option<CudaTools> {
    let from_env = env::var_os("COIL_PTXAS").map(PathBuf::from);
    let on_path = || env::split_paths(&env::var_os("PATH")?).map(|d| d.join("ptxas")).find(|p| p.is_file());
    let ptxas = from_env.or_else(on_path).or_else(pip_ptxas)?;
    let fatbinary = ptxas.with_file_name("fatbinary");
    fatbinary.is_file().then_some(CudaTools { ptxas, fatbinary })
}

/// `ptxas` of PyPI's `nvidia-cuda-nvcc`, in a site-packages folder of `python3`.
fn pip_ptxas() -> Option<PathBuf> {
    let script = "import glob, site; print('\\n'.join(p for d in site.getsitepackages() + [site.getusersitepackages()] \
                  for p in sorted(glob.glob(d + '/nvidia/cu*/bin/ptxas'))))";
    let output = Command::new("python3").args(["-c", script]).output().ok()?;
    let found = String::from_utf8_lossy(&output.stdout).lines().last().map(PathBuf::from)?;
    found.is_file().then_some(found)
}

/// Compiles `ptx` for each of [`CUBIN_ARCHS`] (in parallel) and packs the cubins and the PTX
/// into `fatbin`.
fn compile_fatbin(tools: &CudaTools, ptx: &Path, fatbin: &Path, target_cpu: &str) -> Result<(), String> {
    let cubin = |arch: u32| fatbin.with_file_name(format!("coil_kernels.sm_{arch}.cubin"));
    std::thread::scope(|scope| {
        let runs: Vec<_> = CUBIN_ARCHS
            .iter()
            .map(|&arch| {
                scope.spawn(move || {
                    let mut ptxas = Command::new(&tools.ptxas);
                    ptxas.arg(format!("-arch=sm_{arch}")).arg(ptx).arg("-o").arg(cubin(arch));
                    run(ptxas, &format!("ptxas for sm_{arch}"))
                })
            })
            .collect();
        runs.into_iter().try_for_each(|r| r.join().unwrap_or_else(|_| Err("a ptxas thread panicked".into())))
    })?;
    let virtual_arch = target_cpu.strip_prefix("sm_").unwrap_or("70");
    let mut pack = Command::new(&tools.fatbinary);
    // Uncompressed, so that the tests' stand-in driver reads the kernels' parameters from the PTX.
    pack.arg(format!("--create={}", fatbin.display())).args(["-64", "--compress=false"]);
    for arch in CUBIN_ARCHS {
        pack.arg(format!("--image3=kind=elf,sm={arch},file={}", cubin(arch).display()));
    }
    pack.arg(format!("--image3=kind=ptx,sm={virtual_arch},file={}", ptx.display()));
    run(pack, "fatbinary")
}

fn run(mut command: Command, what: &str) -> Result<(), String> {
    let output =
        command.output().map_err(|e| format!("cannot start {what} ({}): {e}", command.get_program().to_string_lossy()))?;
    if output.status.success() {
        Ok(())
    } else {
        Err(format!("{what} failed: {}", String::from_utf8_lossy(&output.stderr).trim()))
    }
}

fn require_nightly_with_rust_src() {
    let installed = Command::new("rustup")
        .arg(format!("+{}", toolchain()))
        .args(["component", "list", "--installed"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).lines().any(|l| l.starts_with("rust-src")));
    match installed {
        Some(true) => {}
        Some(false) => fail(&format!("the `cuda` feature needs rust-src for {}; install it with: {}", toolchain(), install())),
        None => fail(&format!("the `cuda` feature compiles the kernels with {}; install it with: {}", toolchain(), install())),
    }
}

fn copy(from: &Path, to: &Path) {
    if let Err(e) = std::fs::copy(from, to) {
        fail(&format!("the PTX compiler left no {}: {e}", from.display()));
    }
}

fn fail(message: &str) -> ! {
    eprintln!("error: {message}");
    println!("cargo:warning={message}");
    exit(1);
}
