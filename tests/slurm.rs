//! Slurm for real (issue 27): a one-node cluster started inside the test — `munged`,
//! `slurmctld` and `slurmd` in the foreground, no systemd, ports and state in a temporary
//! folder — the README's array script (taken from the README, scaled down) submitted for the
//! shipped Monte Carlo case, one task cancelled mid-run (`scancel`, after its first chunk) and
//! resubmitted alone, the shards merged with `holewall merge`, and the result checked bit for
//! bit against one unsharded run.
//!
//! Where Slurm and munge are not installed the test says so loudly and passes; under
//! `CI=true` it fails then (`.ci/run` installs Debian's `slurm-wlm` and `munge`).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Samples of the whole run, and tasks of the array (the README's 20000 and 16, scaled down).
const SAMPLES: usize = 2400;
const TASKS: usize = 4;
/// The task cancelled mid-run and resubmitted.
const KILLED: usize = 2;

/// A Slurm or munge program: on the PATH or in the sbin folders Debian puts daemons in.
fn program(name: &str) -> Option<PathBuf> {
    let path = std::env::var("PATH").unwrap_or_default();
    let found = path
        .split(':')
        .chain(["/usr/sbin", "/sbin", "/usr/local/sbin"])
        .map(|d| Path::new(d).join(name))
        .find(|p| p.is_file());
    found
}

/// The daemons, killed when the test ends (passes or panics).
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(String, Child)>,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for (_, c) in self.daemons.iter_mut().rev() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

impl Cluster {
    /// A Slurm command with this cluster's configuration.
    fn cmd(&self, name: &str) -> Command {
        let mut c = Command::new(program(name).unwrap_or_else(|| PathBuf::from(name)));
        c.env("SLURM_CONF", &self.conf).current_dir(&self.dir);
        c
    }

    /// Runs a Slurm command; its stdout, or a panic with its output and the daemons' logs.
    fn run(&self, name: &str, args: &[&str]) -> String {
        let o = self.cmd(name).args(args).output().unwrap();
        if !o.status.success() {
            panic!(
                "{name} {args:?}: {}\n{}\n{}",
                o.status,
                String::from_utf8_lossy(&o.stderr),
                self.logs()
            );
        }
        String::from_utf8_lossy(&o.stdout).into_owned()
    }

    /// The tail of every daemon's log, for a failure's message.
    fn logs(&self) -> String {
        [
            "munged.stderr",
            "munged.log",
            "slurmctld.stderr",
            "slurmctld.log",
            "slurmd.stderr",
            "slurmd.log",
        ]
        .iter()
        .map(|f| {
            let t = std::fs::read_to_string(self.dir.join(f)).unwrap_or_default();
            let lines: Vec<&str> = t.lines().collect();
            format!(
                "--- {f} (last lines)\n{}",
                lines[lines.len().saturating_sub(15)..].join("\n")
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
    }

    /// Waits until the job (or array) has left the queue.
    fn wait_gone(&self, job: &str, limit: Duration) {
        let start = Instant::now();
        loop {
            let q = self.run("squeue", &["-h", "-j", job, "-o", "%i %T"]);
            if q.trim().is_empty() {
                return;
            }
            assert!(
                start.elapsed() < limit,
                "job {job} still queued after {limit:?}:\n{q}\n{}",
                self.logs()
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

/// A free TCP port on the loopback.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn output_of(cmd: &str, args: &[&str]) -> String {
    Command::new(cmd)
        .args(args)
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default()
}

/// Starts munged, slurmctld and slurmd in `dir`; `None` (with the reason) if a program is
/// missing.
fn start(dir: &Path) -> Result<Cluster, String> {
    let needed = [
        "munged",
        "mungekey",
        "slurmctld",
        "slurmd",
        "sbatch",
        "squeue",
        "scancel",
        "sinfo",
    ];
    let missing: Vec<&str> = needed
        .iter()
        .copied()
        .filter(|p| program(p).is_none())
        .collect();
    if !missing.is_empty() {
        return Err(format!("not installed: {}", missing.join(", ")));
    }
    std::fs::create_dir_all(dir.join("state")).unwrap();
    std::fs::create_dir_all(dir.join("spool")).unwrap();
    let munge = dir.join("munge");
    std::fs::create_dir_all(&munge).unwrap();
    use std::os::unix::fs::PermissionsExt;
    // munged wants its socket's folder searchable by all (the key stays 0400).
    std::fs::set_permissions(&munge, std::fs::Permissions::from_mode(0o711)).unwrap();
    let key = munge.join("munge.key");
    let ok = Command::new(program("mungekey").unwrap())
        .args(["--create", "--keyfile"])
        .arg(&key)
        .status()
        .unwrap()
        .success();
    assert!(ok, "mungekey --create failed");
    std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400)).unwrap();
    let socket = munge.join("munge.socket");
    let user = output_of("id", &["-un"]);
    let host = output_of("hostname", &["-s"]);
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (ctld_port, d_port) = (free_port(), free_port());
    let conf = dir.join("slurm.conf");
    let d = dir.display();
    std::fs::write(
        &conf,
        format!(
            "ClusterName=holewall\n\
             SlurmctldHost={host}(127.0.0.1)\n\
             SlurmUser={user}\n\
             SlurmdUser={user}\n\
             AuthType=auth/munge\n\
             AuthInfo=socket={}\n\
             CredType=cred/munge\n\
             StateSaveLocation={d}/state\n\
             SlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\n\
             SlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldPort={ctld_port}\n\
             SlurmdPort={d_port}\n\
             ProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\n\
             SelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\n\
             SchedulerType=sched/builtin\n\
             ReturnToService=2\n\
             MpiDefault=none\n\
             AccountingStorageType=accounting_storage/none\n\
             SlurmctldLogFile={d}/slurmctld.log\n\
             SlurmdLogFile={d}/slurmd.log\n\
             NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN\n\
             PartitionName=debug Nodes={host} Default=YES MaxTime=INFINITE State=UP\n",
            socket.display()
        ),
    )
    .unwrap();
    let mut cluster = Cluster {
        dir: dir.to_path_buf(),
        conf: conf.clone(),
        daemons: Vec::new(),
    };
    let spawn = |name: &str, args: Vec<std::ffi::OsString>| -> Child {
        let err = std::fs::File::create(dir.join(format!("{name}.stderr"))).unwrap();
        Command::new(program(name).unwrap())
            .args(args)
            .env("SLURM_CONF", &conf)
            .stdout(Stdio::null())
            .stderr(err)
            .spawn()
            .unwrap()
    };
    let os = |s: &str| std::ffi::OsString::from(s);
    let mut munged_args = vec![os("-F"), os("--key-file")];
    munged_args.push(key.into());
    munged_args.push(os("--socket"));
    munged_args.push(socket.clone().into());
    munged_args.push(os("--log-file"));
    munged_args.push(dir.join("munged.log").into());
    munged_args.push(os("--pid-file"));
    munged_args.push(munge.join("munged.pid").into());
    munged_args.push(os("--seed-file"));
    munged_args.push(munge.join("munge.seed").into());
    cluster
        .daemons
        .push(("munged".into(), spawn("munged", munged_args)));
    let start = Instant::now();
    while !socket.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "munged did not start:\n{}",
            cluster.logs()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    for daemon in ["slurmctld", "slurmd"] {
        let args = vec![os("-D"), os("-f"), conf.clone().into()];
        cluster.daemons.push((daemon.into(), spawn(daemon, args)));
    }
    // The node comes up idle.
    let start = Instant::now();
    loop {
        let o = cluster
            .cmd("sinfo")
            .args(["-h", "-o", "%T"])
            .output()
            .unwrap();
        let state = String::from_utf8_lossy(&o.stdout).trim().to_string();
        if state == "idle" {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the node is not idle after 60 s (sinfo: {state:?}, {}):\n{}",
            String::from_utf8_lossy(&o.stderr),
            cluster.logs()
        );
        std::thread::sleep(Duration::from_millis(250));
    }
    Ok(cluster)
}

/// The README's array script (the `bash` block under "Many machines (Slurm)"), scaled down
/// and pointed at this build, the repository's case and `out`: each substitution must find
/// its text, so a changed README fails here rather than testing something else.
fn readme_script(out: &Path) -> String {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    let section = readme
        .split("### Many machines (Slurm)")
        .nth(1)
        .expect("the README has a Slurm section");
    let script = section
        .split("```bash\n")
        .nth(1)
        .and_then(|s| s.split("```").next())
        .expect("the Slurm section has a bash block")
        .to_string();
    let repo = env!("CARGO_MANIFEST_DIR");
    let bin = env!("CARGO_BIN_EXE_holewall");
    let mut s = script;
    for (from, to) in [
        ("--array=1-16", format!("--array=1-{TASKS}")),
        ("--cpus-per-task=8", "--cpus-per-task=1".to_string()),
        ("--samples 20000", format!("--samples {SAMPLES}")),
        ("/16 ", format!("/{TASKS} ")),
        (
            "\nholewall ensemble cases/",
            format!("\n{bin} ensemble {repo}/cases/"),
        ),
        ("--out out/", format!("--out {}/", out.display())),
    ] {
        assert!(
            s.contains(from),
            "the README's Slurm script has no {from:?}:\n{s}"
        );
        s = s.replace(from, &to);
    }
    s
}

fn chunks_in(dir: &Path) -> usize {
    std::fs::read_dir(dir.join("chunks"))
        .map(|d| {
            d.filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().ends_with(".json"))
                .count()
        })
        .unwrap_or(0)
}

#[test]
fn the_readme_array_job_on_a_one_node_cluster_merges_to_the_unsharded_run() {
    let dir = std::env::temp_dir().join(format!("hw-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cluster = match start(&dir) {
        Ok(c) => c,
        Err(why) => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true");
            eprintln!(
                "\n*** SLURM TEST SKIPPED: {why} (apt-get install slurm-wlm munge; .ci/run does) ***\n"
            );
            assert!(!ci, "CI=true: Slurm must be installed ({why})");
            return;
        }
    };
    eprintln!(
        "slurm: one-node cluster up in {} ({})",
        dir.display(),
        cluster.run("sinfo", &["--version"]).trim()
    );
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let script = dir.join("holewall_mc.sbatch");
    std::fs::write(&script, readme_script(&out)).unwrap();
    let log = format!("{}/task_%A_%a.out", dir.display());
    let job = cluster
        .run(
            "sbatch",
            &["--parsable", "-o", &log, script.to_str().unwrap()],
        )
        .trim()
        .to_string();
    eprintln!("slurm: submitted array job {job} ({TASKS} tasks, {SAMPLES} samples)");
    // Cancel one task once it has written a chunk and before it has written them all.
    let shard = out.join(format!("mc_shard_{KILLED}"));
    let manifest_chunks = |d: &Path| -> Option<usize> {
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("run.json")).ok()?).ok()?;
        let (k, n) = (KILLED, TASKS);
        let chunks = m["chunks"].as_u64()? as usize;
        Some(k * chunks / n - (k - 1) * chunks / n)
    };
    let start = Instant::now();
    while chunks_in(&shard) == 0 {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "task {KILLED} wrote no chunk in 300 s:\n{}",
            cluster.logs()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    cluster.run("scancel", &[&format!("{job}_{KILLED}")]);
    cluster.wait_gone(&job, Duration::from_secs(600));
    let (done, of) = (
        chunks_in(&shard),
        manifest_chunks(&shard).expect("the shard's run.json"),
    );
    eprintln!("slurm: task {KILLED} cancelled with {done} of its {of} chunks written");
    assert!(
        done < of,
        "task {KILLED} finished before it was cancelled ({done} of {of} chunks): make the shard longer"
    );
    // Resubmitted alone: it continues from its chunks.
    let again = cluster
        .run(
            "sbatch",
            &[
                "--parsable",
                &format!("--array={KILLED}"),
                "-o",
                &log,
                script.to_str().unwrap(),
            ],
        )
        .trim()
        .to_string();
    cluster.wait_gone(&again, Duration::from_secs(600));
    assert_eq!(
        chunks_in(&shard),
        of,
        "the resubmitted task finished its shard"
    );
    eprintln!("slurm: task {KILLED} resubmitted as job {again}, finished its {of} chunks");
    // Merged, against one run on this machine.
    let bin = env!("CARGO_BIN_EXE_holewall");
    let merged = out.join("mc");
    let mut merge = Command::new(bin);
    merge.args(["merge", "--out"]).arg(&merged);
    for k in 1..=TASKS {
        merge.arg(out.join(format!("mc_shard_{k}")));
    }
    let o = merge.arg("--quiet").output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole = dir.join("whole");
    let o = Command::new(bin)
        .args(["ensemble"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/monte_carlo_two_stabilizers.toml"))
        .args([
            "--samples",
            &SAMPLES.to_string(),
            "--seed",
            "1",
            "--backend",
            "auto",
            "--quiet",
            "--out",
        ])
        .arg(&whole)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut compared = Vec::new();
    for e in std::fs::read_dir(&whole).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if name.ends_with(".csv") {
            let (a, b) = (
                std::fs::read(whole.join(&name)).unwrap(),
                std::fs::read(merged.join(&name)).unwrap_or_default(),
            );
            assert!(
                a == b,
                "{name}: the merged run differs from the unsharded one"
            );
            compared.push(name);
        }
    }
    let stats = |d: &Path| -> serde_json::Value {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap())
                .unwrap();
        s["uncertainty"].clone()
    };
    assert!(!stats(&whole).is_null());
    assert_eq!(stats(&whole), stats(&merged), "summary.json's statistics");
    compared.sort();
    eprintln!(
        "slurm: merged {TASKS} shards = the unsharded run, bit for bit: {} and summary.json's statistics",
        compared.join(", ")
    );
    drop(cluster);
    let _ = std::fs::remove_dir_all(&dir);
}
