//! The workbench's server (`flatcut serve`) over real HTTP on loopback: its safety rules (Host
//! checked against DNS rebinding, the token beyond loopback, the 32 MiB body limit, no path
//! outside the page's assets, a malformed design refused with the loader's message while the
//! server lives on), the design saved back to its TOML with comments kept, a style line drawn
//! on the shoe closing a new piece, undo and redo, and downloads byte for byte what `flatcut run`
//! writes.

use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::Duration;

use flatcut_server::{Background, ServeOptions};
use serde_json::{Value, json};

use crate::pipeline::{root, run_project};

/// An HTTP answer: status, headers (lower-case names), body.
struct Answer {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Answer {
    fn json(&self) -> Value {
        serde_json::from_slice(&self.body)
            .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&self.body)))
    }

    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

/// One HTTP/1.1 request on a new connection (`Connection: close`), the answer read to its end.
fn http(
    addr: SocketAddr,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> Answer {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(300))).unwrap();
    let mut head = format!("{method} {path} HTTP/1.1\r\nConnection: close\r\n");
    if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        head.push_str(&format!("Host: 127.0.0.1:{}\r\n", addr.port()));
    }
    for (k, v) in headers {
        head.push_str(&format!("{k}: {v}\r\n"));
    }
    head.push_str(&format!("Content-Length: {}\r\n\r\n", body.len()));
    s.write_all(head.as_bytes()).unwrap();
    // The server may answer (413) before it has read a large body: a write error then is fine.
    let _ = s.write_all(body);
    let mut r = BufReader::new(s);
    let mut line = String::new();
    r.read_line(&mut line).unwrap();
    let status: u16 = line.split(' ').nth(1).unwrap().parse().unwrap();
    let mut headers = Vec::new();
    loop {
        let mut l = String::new();
        r.read_line(&mut l).unwrap();
        let l = l.trim_end();
        if l.is_empty() {
            break;
        }
        let (k, v) = l.split_once(':').unwrap();
        headers.push((k.trim().to_ascii_lowercase(), v.trim().to_string()));
    }
    let chunked = headers
        .iter()
        .any(|(k, v)| k == "transfer-encoding" && v.contains("chunked"));
    let mut body = Vec::new();
    if chunked {
        loop {
            let mut size = String::new();
            r.read_line(&mut size).unwrap();
            let n = usize::from_str_radix(size.trim(), 16).unwrap();
            let mut chunk = vec![0; n + 2];
            r.read_exact(&mut chunk).unwrap();
            if n == 0 {
                break;
            }
            body.extend_from_slice(&chunk[..n]);
        }
    } else {
        r.read_to_end(&mut body).unwrap();
    }
    Answer {
        status,
        headers,
        body,
    }
}

fn get(addr: SocketAddr, path: &str) -> Answer {
    http(addr, "GET", path, &[], b"")
}

fn send(addr: SocketAddr, method: &str, path: &str, v: &Value) -> Answer {
    http(
        addr,
        method,
        path,
        &[("Content-Type", "application/json")],
        v.to_string().as_bytes(),
    )
}

/// The sizes the shoe is graded in (40, 42, 44): the workbench flattens each.
const SHOE_SIZES: usize = 3;

/// The shoe project copied into a temporary directory (the workbench saves into it).
fn shoe() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for f in ["project.toml", "design.toml"] {
        std::fs::copy(root().join("patterns/shoe").join(f), dir.path().join(f)).unwrap();
    }
    dir
}

fn serve(input: &Path) -> Background {
    Background::start(&ServeOptions {
        input: Some(input.to_path_buf()),
        port: 0,
        bind: None,
    })
    .unwrap()
}

/// Three points of the shoe's surface across the vamp near x = 210 mm, in front of the vamp's
/// `at` (so the vamp keeps the part beside its lapped lines to the quarters): the featherline on
/// each side (on the surface boundary) and the top, taken from the mesh the server traces lines
/// on.
pub fn vamp_line(regions: &Value) -> Vec<[f64; 3]> {
    let p = regions["parts"][0]["mesh"]["positions"].as_array().unwrap();
    let verts: Vec<[f64; 3]> = p
        .chunks(3)
        .map(|c| {
            [
                c[0].as_f64().unwrap(),
                c[1].as_f64().unwrap(),
                c[2].as_f64().unwrap(),
            ]
        })
        .collect();
    let nearest = |t: [f64; 3]| {
        *verts
            .iter()
            .min_by(|a, b| {
                let d = |v: &[f64; 3]| (0..3).map(|k| (v[k] - t[k]).powi(2)).sum::<f64>();
                d(a).total_cmp(&d(b))
            })
            .unwrap()
    };
    vec![
        nearest([210.0, -60.0, 0.0]),
        nearest([210.0, 0.0, 55.0]),
        nearest([210.0, 60.0, 0.0]),
    ]
}

/// Host names that are not the server's get 421 (a DNS-rebinding page's requests carry its own
/// name); the loopback names at the server's port pass. Only the page's assets are served.
#[test]
fn serve_refuses_foreign_hosts_and_serves_no_path_beyond_its_assets() {
    let dir = shoe();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let port = a.port().to_string();
    for bad in ["evil.example", "evil.example:80", "localhost.evil.example"] {
        let r = http(a, "GET", "/api/health", &[("Host", bad)], b"");
        assert_eq!(r.status, 421, "{bad}");
    }
    let r = http(
        a,
        "GET",
        "/api/health",
        &[(
            "Host",
            &format!("127.0.0.1:{}", port.as_str().parse::<u16>().unwrap() + 1),
        )],
        b"",
    );
    assert_eq!(r.status, 421, "another port");
    for ok in [
        format!("localhost:{port}"),
        format!("127.0.0.1:{port}"),
        format!("[::1]:{port}"),
    ] {
        let r = http(a, "GET", "/api/health", &[("Host", &ok)], b"");
        assert_eq!(r.status, 200, "{ok}");
        assert_eq!(r.json()["status"], "ok");
    }
    let page = get(a, "/");
    assert_eq!(page.status, 200);
    assert!(String::from_utf8_lossy(&page.body).contains("/app.js"));
    assert_eq!(get(a, "/app.js").status, 200);
    for path in [
        "/../Cargo.toml",
        "/%2e%2e/%2e%2e/Cargo.toml",
        "/project.toml",
        "/design.toml",
        "/assets/app.js",
        "/..%2fproject.toml",
        "/etc/passwd",
        "/api/../project.toml",
    ] {
        let r = get(a, path);
        assert_eq!(
            r.status,
            404,
            "{path}: {}",
            String::from_utf8_lossy(&r.body)
        );
        assert!(!String::from_utf8_lossy(&r.body).contains("[material]"));
    }
    srv.stop().unwrap();
}

/// Beyond loopback every request needs the printed token: none or a wrong one is 401; a bearer
/// header, the custom header or the query (which sets the cookie the page then uses) pass.
#[test]
fn serve_beyond_loopback_needs_the_token() {
    let dir = shoe();
    let srv = Background::start(&ServeOptions {
        input: Some(dir.path().join("project.toml")),
        port: 0,
        bind: Some("0.0.0.0".parse().unwrap()),
    })
    .unwrap();
    let token = srv
        .listening
        .token
        .clone()
        .expect("a token beyond loopback");
    assert_eq!(token.len(), 32);
    assert!(srv.listening.url.contains(&token));
    let a = SocketAddr::from(([127, 0, 0, 1], srv.addr().port()));
    assert_eq!(get(a, "/api/health").status, 401);
    assert_eq!(get(a, "/").status, 401);
    assert_eq!(get(a, "/api/health?token=nope").status, 401);
    let auth = format!("Bearer {token}");
    assert_eq!(
        http(a, "GET", "/api/health", &[("Authorization", &auth)], b"").status,
        200
    );
    assert_eq!(
        http(a, "GET", "/api/health", &[("X-Flatcut-Token", &token)], b"").status,
        200
    );
    let r = get(a, &format!("/?token={token}"));
    assert_eq!(r.status, 200);
    let cookie = r
        .header("set-cookie")
        .expect("the page gets the token as a cookie");
    assert!(
        cookie.contains("HttpOnly") && cookie.contains("SameSite=Strict"),
        "{cookie}"
    );
    let c = cookie.split(';').next().unwrap();
    assert_eq!(
        http(a, "GET", "/api/health", &[("Cookie", c)], b"").status,
        200
    );
    srv.stop().unwrap();
    // Loopback needs none.
    let srv = serve(&dir.path().join("project.toml"));
    assert!(srv.listening.token.is_none());
    assert_eq!(get(srv.addr(), "/api/health").status, 200);
}

/// A body over 32 MiB is 413 and changes nothing; a malformed design is 400 with the loader's
/// located message, nothing changes, and the server goes on answering.
#[test]
fn serve_refuses_large_bodies_and_malformed_designs_and_lives_on() {
    let dir = shoe();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let before = get(a, "/api/design").json();
    let big = vec![b' '; 33 * 1024 * 1024];
    let r = http(
        a,
        "PUT",
        "/api/design",
        &[("Content-Type", "application/json")],
        &big,
    );
    assert_eq!(r.status, 413);
    // Not JSON at all: located in the body.
    let r = http(a, "PUT", "/api/design", &[], b"{\"units\": ");
    assert_eq!(r.status, 400);
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .starts_with("request body:1:"),
        "{}",
        r.json()
    );
    // A piece's allowance of the wrong type: the design loader's message, with the design file,
    // line and column as the command line reports them.
    let mut bad = before.clone();
    bad["part"][0]["piece"][1]["seam_allowance_mm"] = json!("eight");
    let r = send(a, "PUT", "/api/design", &bad);
    assert_eq!(r.status, 400);
    let msg = r.json()["error"].as_str().unwrap().to_string();
    let file = dir.path().join("design.toml").display().to_string();
    assert!(msg.starts_with(&format!("{file}:")), "{msg}");
    assert!(msg.contains("invalid type"), "{msg}");
    // A line that does not close: the loader's message names the part, the line and the end.
    let mut loose = before.clone();
    loose["part"][0]["line"][3]["points"] = json!([[-4, 0, 0], [-6.3, 0, 14.4]]);
    loose["part"][0]["line"][3]["notches"] = json!([]);
    let r = send(a, "PUT", "/api/design?regions=name", &loose);
    assert_eq!(r.status, 400);
    let msg = r.json()["error"].as_str().unwrap().to_string();
    assert!(
        msg.contains("part 0 'upper': line 3 'back'") && msg.contains("does not close a region"),
        "{msg}"
    );
    assert_eq!(get(a, "/api/health").status, 200);
    assert_eq!(get(a, "/api/design").json(), before, "nothing changed");
    assert_eq!(get(a, "/api/health").json()["revision"], 1);
    srv.stop().unwrap();
}

/// A changed value saved back keeps every comment and every untouched key of the file.
#[test]
fn serve_saves_the_design_back_keeping_comments_and_untouched_keys() {
    let dir = shoe();
    let design = dir.path().join("design.toml");
    let original = std::fs::read_to_string(&design).unwrap();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let mut tree = get(a, "/api/design").json();
    assert_eq!(tree["part"][0]["piece"][1]["name"], "vamp");
    tree["part"][0]["piece"][1]["seam_allowance_mm"] = json!(9);
    let r = send(a, "PUT", "/api/design", &tree);
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    assert_eq!(r.json()["saved"], false);
    assert_eq!(
        std::fs::read_to_string(&design).unwrap(),
        original,
        "not saved yet"
    );
    let r = http(a, "POST", "/api/design/save", &[], b"");
    assert_eq!(r.status, 200);
    assert_eq!(r.json()["saved"], true);
    let saved = std::fs::read_to_string(&design).unwrap();
    let diff: Vec<(&str, &str)> = original
        .lines()
        .zip(saved.lines())
        .filter(|(x, y)| x != y)
        .collect();
    assert_eq!(original.lines().count(), saved.lines().count());
    assert_eq!(diff.len(), 1, "{diff:?}");
    assert_eq!(diff[0].1, "seam_allowance_mm = 9");
    assert!(saved.contains("# Generated by make.py; do not edit by hand."));
    assert!(saved.contains(
        "# The toe cap along the old toe-cap stitch line, featherline to featherline; lapped: the"
    ));
    srv.stop().unwrap();
}

/// A line drawn across the vamp closes a new region: it gets a piece of its own at once, the
/// live flattening has five pieces in the base size (the graded run's own base-size pieces),
/// every size has five and a new mating seam per size,
/// within the leather's limits; undo brings the four pieces back and redo the five; a loose line
/// is refused with the loader's message.
#[test]
fn serve_a_line_across_the_vamp_makes_a_fifth_piece() {
    let dir = shoe();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    // Live, the graded shoe is flattened in its base size, 42.
    let f = send(a, "POST", "/api/flatten", &json!({}));
    assert_eq!(f.status, 200, "{}", String::from_utf8_lossy(&f.body));
    let f = f.json();
    assert_eq!(f["pieces"].as_array().unwrap().len(), 4);
    assert_eq!(f["sizes"], json!(["40", "42", "44"]));
    assert_eq!(f["pieces"][0]["name"], "toe cap 42");
    assert_eq!(f["pieces"][0]["part"], "upper");
    assert_eq!(f["pieces"][0]["size"], "42");
    assert_eq!(
        send(a, "POST", "/api/flatten?sizes=some", &json!({})).status,
        400
    );
    let regions = get(a, "/api/regions").json();
    assert_eq!(regions["parts"][0]["regions"].as_array().unwrap().len(), 4);
    let pts = vamp_line(&regions);
    // A line stopping short of the featherline does not close.
    let r = send(
        a,
        "POST",
        "/api/lines",
        &json!({"part": "upper", "name": "cut", "points": [pts[0], pts[1]]}),
    );
    assert_eq!(r.status, 400);
    assert!(
        r.json()["error"]
            .as_str()
            .unwrap()
            .contains("does not close a region"),
        "{}",
        r.json()
    );
    let r = send(
        a,
        "POST",
        "/api/lines",
        &json!({"part": "upper", "name": "cut", "points": pts}),
    );
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let r = r.json();
    assert_eq!(r["added"], json!(["upper 1"]));
    let tree = get(a, "/api/design").json();
    let new = &tree["part"][0]["piece"][4];
    assert_eq!(new["name"], "upper 1");
    // It takes the vamp's settings (the piece across the new line).
    assert_eq!(new["seam_allowance_mm"], 8);
    assert_eq!(new["pairs"], 1);
    let base = send(a, "POST", "/api/flatten", &json!({})).json();
    assert_eq!(base["pieces"].as_array().unwrap().len(), 5);
    let f = send(a, "POST", "/api/flatten?sizes=all", &json!({})).json();
    let pieces = f["pieces"].as_array().unwrap();
    assert_eq!(pieces.len(), 5 * SHOE_SIZES);
    // The base size live is the base size of the graded run.
    let upper = |v: &Value| {
        v["pieces"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == "upper 1 42")
            .unwrap()["stretch_max_pct"]
            .clone()
    };
    assert_eq!(upper(&base), upper(&f));
    for p in pieces {
        assert!(p["within_limits"].as_bool().unwrap(), "{}", p["name"]);
        let faces = p["faces"].as_u64().unwrap() as usize;
        assert_eq!(p["mesh"]["strain"].as_array().unwrap().len(), faces);
        assert_eq!(p["mesh"]["triangles"].as_array().unwrap().len(), 3 * faces);
        assert!(p["stretch_max_pct"].as_f64().unwrap() <= 12.0);
        assert!(p["compress_max_pct"].as_f64().unwrap() <= 2.0);
    }
    let seams = f["mating_seams"].as_array().unwrap();
    let cut = seams
        .iter()
        .find(|s| s["name"] == "cut 42")
        .expect("the new line is a seam in every size");
    assert!(cut["mismatch_mm"].as_f64().unwrap() < 0.1, "{cut}");
    let mut sides: Vec<&str> = cut["pieces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    sides.sort();
    assert_eq!(sides, ["upper 1 42", "vamp 42"]);
    // Undo, redo.
    assert_eq!(http(a, "POST", "/api/design/undo", &[], b"").status, 200);
    assert_eq!(
        send(a, "POST", "/api/flatten", &json!({})).json()["pieces"]
            .as_array()
            .unwrap()
            .len(),
        4
    );
    assert_eq!(http(a, "POST", "/api/design/redo", &[], b"").status, 200);
    assert_eq!(get(a, "/api/design").json(), tree);
    // The region is renamed by a click in it.
    let inner = get(a, "/api/regions").json()["parts"][0]["regions"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["piece"] == "upper 1")
        .unwrap()["inner"]
        .clone();
    let r = send(
        a,
        "POST",
        "/api/regions/name",
        &json!({"part": "upper", "at": inner, "name": "toe box"}),
    );
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    assert_eq!(
        get(a, "/api/design").json()["part"][0]["piece"][4]["name"],
        "toe box"
    );
    srv.stop().unwrap();
}

/// The downloads are the files `flatcut run` writes for the same project, byte for byte; the
/// HP-GL is `flatcut hpgl layout-1.svg`'s.
#[test]
fn serve_downloads_are_the_bytes_the_cli_writes() {
    let dir = shoe();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let out = tempfile::tempdir().unwrap();
    run_project("patterns/shoe/project.toml", out.path(), &["--no-send"]);
    for (route, file) in [
        ("/api/pattern.svg", "pattern.svg"),
        ("/api/pattern.dxf", "pattern.dxf"),
        ("/api/layout.svg", "layout-1.svg"),
        ("/api/layout.dxf?sheet=1", "layout-1.dxf"),
        ("/api/job.gcode", "job-1.gcode"),
        ("/api/summary.json", "summary.json"),
    ] {
        let r = get(a, route);
        assert_eq!(r.status, 200, "{route}");
        let want = std::fs::read(out.path().join(file)).unwrap();
        assert!(r.body == want, "{route} differs from flatcut run's {file}");
    }
    assert_eq!(get(a, "/api/job.gcode?sheet=9").status, 404);
    assert_eq!(get(a, "/api/job.gcode?sheet=0").status, 400);
    let plt = out.path().join("job-1.plt");
    let layout = out.path().join("layout-1.svg");
    crate::pipeline::run_cli(&[
        "hpgl",
        layout.to_str().unwrap(),
        "--profile",
        "vinyl",
        "-o",
        plt.to_str().unwrap(),
    ]);
    let r = get(a, "/api/job.plt");
    assert_eq!(r.status, 200);
    assert!(
        r.body == std::fs::read(&plt).unwrap(),
        "job.plt differs from flatcut hpgl's"
    );
    srv.stop().unwrap();
}

/// Every page hears the design change on /api/events, and a stopped server ends its streams.
#[test]
fn serve_events_tell_every_page_the_design_changed() {
    let dir = shoe();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let mut s = TcpStream::connect(a).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    write!(
        s,
        "GET /api/events HTTP/1.1\r\nHost: localhost:{}\r\n\r\n",
        a.port()
    )
    .unwrap();
    let mut r = BufReader::new(s);
    let mut seen = String::new();
    let mut saw = |what: &str, r: &mut BufReader<TcpStream>| {
        while !seen.contains(what) {
            let mut l = String::new();
            assert!(
                r.read_line(&mut l).unwrap() > 0,
                "the stream ended before {what}"
            );
            seen.push_str(&l);
        }
    };
    saw("event: hello", &mut r);
    let mut tree = get(a, "/api/design").json();
    tree["part"][0]["piece"][0]["seam_allowance_mm"] = json!(7);
    assert_eq!(send(a, "PUT", "/api/design", &tree).status, 200);
    saw("event: design", &mut r);
    saw("\"revision\":2", &mut r);
    // Stopping ends the stream (an open page does not hold the server up).
    srv.stop().unwrap();
    let mut rest = String::new();
    r.read_to_string(&mut rest).unwrap();
}

/// The lampshade project copied into a temporary directory (the jobs' journals go beside it).
fn lampshade() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for f in ["project.toml", "design.toml", "plotter-a0.toml"] {
        std::fs::copy(
            root().join("patterns/lampshade").join(f),
            dir.path().join(f),
        )
        .unwrap();
    }
    dir
}

/// Polls `GET /api/jobs/{id}` until `done` holds (at most 120 s).
fn job_until(a: SocketAddr, id: u64, what: &str, done: impl Fn(&Value) -> bool) -> Value {
    let t0 = std::time::Instant::now();
    loop {
        let j = get(a, &format!("/api/jobs/{id}")).json();
        if done(&j) {
            return j;
        }
        let st = j["state"].as_str().unwrap();
        assert!(
            !["done", "failed", "stopped"].contains(&st) || what == "ended",
            "job {id} ended before it {what}: {j}"
        );
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "job {id} never {what}: {j}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Job lines of the lampshade's sheet before its outlines (its labels, drawn stroke over stroke).
const CUT_LAYER: u64 = 1500;

fn lines_done(j: &Value) -> u64 {
    j["progress"]["lines_done"].as_u64().unwrap_or(0)
}

/// Whether two positions agree within a step of the machine (the simulator moves in whole steps,
/// the job's coordinates are not on their grid).
fn near(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= 0.01)
}

/// The job's motions `(text, end)` of lines `0..end` that move the machine by at least a step
/// (a shorter move rounds to where the machine stands, and the simulator makes none).
fn motions_before(job: &flatcut_grbl::Job, end: usize) -> Vec<(String, [f64; 3])> {
    (0..end.min(job.len()))
        .filter(|&i| job.lines[i].moves && job.lines[i].length >= 0.01)
        .map(|i| (job.lines[i].text.clone(), job.end_of(i)))
        .collect()
}

/// Checks that the simulator's `motions` (the JSON of `GET /api/devices/sim`) since a resume from
/// job line `from` are the travel to that line's start (at most a lift, a traverse and a plunge),
/// then the job's motions from that line on, each once, in order.
fn assert_runs_from(motions: &[Value], job: &flatcut_grbl::Job, from: usize) {
    let xyz = |v: &Value| -> [f64; 3] { std::array::from_fn(|i| v[i].as_f64().unwrap()) };
    let mut ran: Vec<(String, [f64; 3], [f64; 3])> = Vec::new();
    for m in motions {
        let (t, a, b) = (m["text"].as_str().unwrap(), xyz(&m["from"]), xyz(&m["to"]));
        if near(a, b) {
            continue;
        }
        // A line stopped part-way and completed later is one motion.
        match ran.last_mut() {
            Some(l) if l.0 == t && near(l.2, a) => l.2 = b,
            _ => ran.push((t.to_string(), a, b)),
        }
    }
    let want: Vec<(String, [f64; 3])> = motions_before(job, job.len())
        .into_iter()
        .skip(motions_before(job, from).len())
        .collect();
    let line = job.lines[from].source_line;
    assert!(
        ran.len() >= want.len() && ran.len() <= want.len() + 3,
        "{} motions ran from line {line}; the job has {} from it (and a travel of at most 3)",
        ran.len(),
        want.len()
    );
    let tail = &ran[ran.len() - want.len()..];
    for (k, (t, to)) in want.iter().enumerate() {
        assert_eq!(&tail[k].0, t, "motion {k} from line {line}");
        assert!(
            near(tail[k].2, *to),
            "motion {k}: {:?} vs {to:?}",
            tail[k].2
        );
    }
}

/// The device panel over HTTP on the lampshade: the project's device is the embedded
/// simulator; a job streams from the run's G-code, a second is refused while it runs; a stop
/// leaves the tool off. After the simulator was closed (its position lost) a resume asks
/// whether the origin is where it was and on a yes completes the job. A job paused (the machine
/// holds where it is) and resumed runs to its end, motion for motion the G-code's moves. Then the server is stopped during a job: the job stops with the tool off, and the
/// simulator executed exactly the lines before the one the journal says it stopped in, and that
/// one up to where the journal says. (Four jobs at 200× real time on a 1 Mbaud link.)
#[test]
fn serve_streams_jobs_to_the_simulator_and_stops_them_with_the_tool_off() {
    let dir = lampshade();
    let srv = serve(&dir.path().join("project.toml"));
    let app = srv.app.clone();
    let a = srv.addr();
    let d = get(a, "/api/devices").json();
    assert_eq!(d["project_device"], "simulator");
    let ids: Vec<&Value> = d["devices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| &x["id"])
        .collect();
    assert!(ids.contains(&&json!("simulator")), "{d}");
    assert_eq!(d["open"]["open"], false);
    let c = send(
        a,
        "POST",
        "/api/devices/connect",
        &json!({"device": "simulator", "speed": 200, "baud": 1_000_000}),
    );
    assert_eq!(c.status, 200, "{}", String::from_utf8_lossy(&c.body));
    assert_eq!(c.json()["controller"]["version"], "1.1h");
    let gcode = get(a, "/api/job.gcode").body;
    let job = flatcut_grbl::Job::parse(std::str::from_utf8(&gcode).unwrap()).unwrap();
    // A job, and a second refused while it runs.
    let r = send(a, "POST", "/api/jobs", &json!({"sheet": 1}));
    assert_eq!(r.status, 201, "{}", String::from_utf8_lossy(&r.body));
    assert_eq!(r.json()["id"], 1);
    assert_eq!(send(a, "POST", "/api/jobs", &json!({})).status, 409);
    assert_eq!(get(a, "/api/jobs/9").status, 404);
    // Into the outlines (the labels before them pass over their own strokes, where a resume
    // cannot tell which stroke ran and refuses).
    job_until(a, 1, "reached the outlines", |j| lines_done(j) > CUT_LAYER);
    assert_eq!(send(a, "POST", "/api/jobs/1/stop", &json!({})).status, 200);
    let stopped = job_until(a, 1, "stopped", |j| j["state"] == "stopped");
    assert!(
        stopped["message"].as_str().unwrap().contains("tool off"),
        "{stopped}"
    );
    // The simulator closed: a new one starts with its position lost, so the resume asks.
    let closed = send(a, "POST", "/api/devices/close", &json!({})).json();
    assert_eq!(closed["closed"], "simulator");
    assert!(closed["sim"]["motions"].as_array().unwrap().len() > 1000);
    let r = send(a, "POST", "/api/jobs", &json!({"sheet": 1, "resume": true}));
    assert_eq!(r.status, 201, "{}", String::from_utf8_lossy(&r.body));
    let asked = job_until(a, 2, "asked", |j| !j["question"].is_null());
    assert_eq!(asked["state"], "asking");
    let q = &asked["question"];
    assert!(
        q["text"]
            .as_str()
            .unwrap()
            .contains("position is not known"),
        "{q}"
    );
    assert_eq!(q["prompt"], "Is the work origin where it was? [y/N] ");
    let r = send(
        a,
        "POST",
        "/api/jobs/2/answer",
        &json!({"question": q["id"], "yes": true}),
    );
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    assert_eq!(
        send(
            a,
            "POST",
            "/api/jobs/2/answer",
            &json!({"question": q["id"], "yes": true})
        )
        .status,
        409,
        "a question is answered once"
    );
    let done = job_until(a, 2, "ended", |j| {
        ["done", "failed", "stopped"].contains(&j["state"].as_str().unwrap())
    });
    assert_eq!(done["state"], "done", "{done}");
    assert!(done["report"]["previously_done"].as_u64().unwrap() > CUT_LAYER);
    let before = get(a, "/api/devices/sim").json()["motions"]
        .as_array()
        .unwrap()
        .len();
    // A whole job, paused and resumed once: the simulator made the G-code's moves, each once,
    // in order.
    assert_eq!(send(a, "POST", "/api/jobs", &json!({})).status, 201);
    job_until(a, 3, "ran 500 lines", |j| lines_done(j) > 500);
    assert_eq!(send(a, "POST", "/api/jobs/3/hold", &json!({})).status, 200);
    let held = job_until(a, 3, "held", |j| {
        j["state"] == "held" && j["progress"]["machine_state"] == "Hold:0"
    });
    std::thread::sleep(Duration::from_millis(300));
    let still = get(a, "/api/jobs/3").json();
    assert_eq!(still["progress"]["position"], held["progress"]["position"]);
    assert_eq!(
        still["progress"]["lines_done"],
        held["progress"]["lines_done"]
    );
    assert_eq!(
        send(a, "POST", "/api/jobs/3/resume", &json!({})).status,
        200
    );
    let on = held["progress"]["lines_done"].as_u64().unwrap() + 20;
    job_until(a, 3, "went on", |j| {
        j["state"] == "running" && lines_done(j) > on
    });
    let whole = job_until(a, 3, "ended", |j| {
        ["done", "failed", "stopped"].contains(&j["state"].as_str().unwrap())
    });
    assert_eq!(whole["state"], "done", "{whole}");
    let after = get(a, "/api/devices/sim").json()["motions"]
        .as_array()
        .unwrap()
        .len();
    // The server stopped during a job.
    assert_eq!(send(a, "POST", "/api/jobs", &json!({})).status, 201);
    job_until(a, 4, "reached the outlines", |j| lines_done(j) > CUT_LAYER);
    srv.stop().unwrap();
    let fourth = app.devices.job(4).unwrap();
    assert_eq!(fourth["state"], "stopped", "{fourth}");
    let sim = app.devices.last_sim().unwrap().trace;
    assert_ran_whole_job(&sim[before..after], &job);
    // The journal and the simulator agree: the machine stopped part-way through the line the
    // journal names (`P`), where it says, having run every line before it and nothing after.
    assert_stopped_as_journal_says(&sim[after..], &job, &dir.path().join("job-1.gcode.journal"));
}

/// "Resume from line N" in the device panel (`POST /api/jobs` with `resume_from`, a line of the
/// sheet's file): refused with 400 when nothing is sent from that line on; after a stop, the job
/// continues from that line whatever the journal says (the operator looked at the work), as
/// `flatcut send --resume-from` does: after the same question on the work origin (the panel's
/// simulator counts as restarted), the lines before it count as run, the simulator runs the
/// G-code's motions from that line on, each once, and the journal ends complete.
#[test]
fn serve_resumes_a_job_from_the_line_the_operator_names() {
    let dir = lampshade();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let c = send(
        a,
        "POST",
        "/api/devices/connect",
        &json!({"device": "simulator", "speed": 200, "baud": 1_000_000}),
    );
    assert_eq!(c.status, 200, "{}", String::from_utf8_lossy(&c.body));
    let gcode = get(a, "/api/job.gcode").body;
    let text = std::str::from_utf8(&gcode).unwrap();
    let job = flatcut_grbl::Job::parse(text).unwrap();
    let last = text.lines().count();
    let r = send(
        a,
        "POST",
        "/api/jobs",
        &json!({"sheet": 1, "resume_from": last + 1}),
    );
    assert_eq!(r.status, 400, "{}", String::from_utf8_lossy(&r.body));
    assert!(
        String::from_utf8_lossy(&r.body)
            .contains(&format!("nothing to send from line {}", last + 1)),
        "{}",
        String::from_utf8_lossy(&r.body)
    );
    // A job stopped in its outlines.
    assert_eq!(
        send(a, "POST", "/api/jobs", &json!({"sheet": 1})).status,
        201
    );
    job_until(a, 1, "reached the outlines", |j| lines_done(j) > CUT_LAYER);
    assert_eq!(send(a, "POST", "/api/jobs/1/stop", &json!({})).status, 200);
    job_until(a, 1, "stopped", |j| j["state"] == "stopped");
    let before = get(a, "/api/devices/sim").json()["motions"]
        .as_array()
        .unwrap()
        .len();
    // The operator continues from a line near the end of the file: a comment line names the
    // next line sent.
    let from = job.len() - 40;
    let line = job.lines[from].source_line;
    let comment = (1..line)
        .rev()
        .find(|&l| text.lines().nth(l - 1).is_some_and(|t| t.starts_with('(')))
        .filter(|&l| job.first_line_from(l) == Some(from));
    let named = comment.unwrap_or(line);
    let r = send(
        a,
        "POST",
        "/api/jobs",
        &json!({"sheet": 1, "resume_from": named}),
    );
    assert_eq!(r.status, 201, "{}", String::from_utf8_lossy(&r.body));
    assert_eq!(r.json()["resume_from"], named);
    assert_eq!(r.json()["resume"], true);
    // The same question as any resume on a controller whose position may be lost.
    let asked = job_until(a, 2, "asked", |j| !j["question"].is_null());
    let q = &asked["question"];
    assert!(
        q["text"].as_str().unwrap().contains(&format!(
            "continues with line {}",
            job.lines[from].source_line
        )),
        "{q}"
    );
    let r = send(
        a,
        "POST",
        "/api/jobs/2/answer",
        &json!({"question": q["id"], "yes": true}),
    );
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let done = job_until(a, 2, "ended", |j| {
        ["done", "failed", "stopped"].contains(&j["state"].as_str().unwrap())
    });
    assert_eq!(done["state"], "done", "{done}");
    assert_eq!(done["report"]["previously_done"], from);
    assert!(done["in_doubt"].is_null(), "{done}");
    let sim = get(a, "/api/devices/sim").json();
    assert_runs_from(&sim["motions"].as_array().unwrap()[before..], &job, from);
    let journal = flatcut_grbl::Journal::read(dir.path().join("job-1.gcode.journal")).unwrap();
    assert!(journal.finished);
    srv.stop().unwrap();
}

/// Environment variable naming the project directory of [`serve_child_process`].
const SERVE_CHILD_ENV: &str = "FLATCUT_SERVE_CHILD_DIR";

/// The workbench's server in a process of its own for
/// [`serve_names_the_lines_in_doubt_after_a_crash_and_resumes_from_the_operators_line`], which
/// kills it. It says where it listens on stderr and ends by itself after two minutes. Without
/// the variable set it is the parent's run and does nothing.
#[test]
fn serve_child_process() {
    let Some(dir) = std::env::var_os(SERVE_CHILD_ENV) else {
        return;
    };
    let srv = serve(&Path::new(&dir).join("project.toml"));
    eprintln!("serving at {}", srv.addr());
    std::thread::sleep(Duration::from_secs(120));
}

/// Kills the child process when dropped (a test that fails leaves no server behind).
struct Killed(std::process::Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A server killed during a job (a power cut: nothing stopped, nothing closed, the simulator
/// gone with it; here while the job is held with lines queued) leaves a journal whose last
/// acknowledged lines may or may not have run. On the next server, the resume refuses to guess: the job fails naming those lines in
/// its `in_doubt` (from the journal's first unconfirmed line, as the page shows them), and
/// continues from the line the operator names after the origin question, running the G-code's
/// motions from that line on, each once, to the journal's end.
#[test]
fn serve_names_the_lines_in_doubt_after_a_crash_and_resumes_from_the_operators_line() {
    let dir = lampshade();
    let mut child =
        crate::stream::child_test("serve::serve_child_process", SERVE_CHILD_ENV, dir.path());
    let mut child = Killed(
        child
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let stderr = BufReader::new(child.0.stderr.take().unwrap());
    let a: SocketAddr = stderr
        .lines()
        .map_while(Result::ok)
        .find_map(|l| {
            l.strip_prefix("serving at ")
                .map(|s| s.trim().parse().unwrap())
        })
        .expect("the server says where it listens");
    let c = send(
        a,
        "POST",
        "/api/devices/connect",
        &json!({"device": "simulator", "speed": 200, "baud": 1_000_000}),
    );
    assert_eq!(c.status, 200, "{}", String::from_utf8_lossy(&c.body));
    let gcode = get(a, "/api/job.gcode").body;
    let job = flatcut_grbl::Job::parse(std::str::from_utf8(&gcode).unwrap()).unwrap();
    assert_eq!(
        send(a, "POST", "/api/jobs", &json!({"sheet": 1})).status,
        201
    );
    job_until(a, 1, "reached the outlines", |j| lines_done(j) > CUT_LAYER);
    // The power fails while the job is held with lines queued (acknowledged, not run); a hold
    // where the planner had drained (a dwell) is let go and tried again further on.
    let mut queued = false;
    for _ in 0..20 {
        assert_eq!(send(a, "POST", "/api/jobs/1/hold", &json!({})).status, 200);
        let held = job_until(a, 1, "held", |j| {
            j["state"] == "held" && j["progress"]["machine_state"] == "Hold:0"
        });
        if held["progress"]["lines_acked"].as_u64() > held["progress"]["lines_done"].as_u64() {
            queued = true;
            break;
        }
        assert_eq!(
            send(a, "POST", "/api/jobs/1/resume", &json!({})).status,
            200
        );
        let on = lines_done(&held) + 30;
        job_until(a, 1, "went on", |j| lines_done(j) > on);
    }
    assert!(queued, "every hold found the planner drained");
    drop(child);
    let journal_path = dir.path().join("job-1.gcode.journal");
    let journal = flatcut_grbl::Journal::read(&journal_path).unwrap();
    assert!(!journal.finished && journal.stop.is_none());
    let first = *journal
        .unconfirmed
        .first()
        .expect("lines acknowledged and not known to have run");
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let c = send(
        a,
        "POST",
        "/api/devices/connect",
        &json!({"device": "simulator", "speed": 200, "baud": 1_000_000}),
    );
    assert_eq!(c.status, 200, "{}", String::from_utf8_lossy(&c.body));
    let r = send(a, "POST", "/api/jobs", &json!({"sheet": 1, "resume": true}));
    assert_eq!(r.status, 201, "{}", String::from_utf8_lossy(&r.body));
    let refused = job_until(a, 1, "ended", |j| {
        ["done", "failed", "stopped"].contains(&j["state"].as_str().unwrap())
    });
    assert_eq!(refused["state"], "failed", "{refused}");
    assert!(
        refused["message"]
            .as_str()
            .unwrap()
            .contains("cannot tell where to resume"),
        "{refused}"
    );
    let doubt = &refused["in_doubt"];
    let (from, to) = (
        doubt["from"].as_u64().unwrap() as usize,
        doubt["to"].as_u64().unwrap() as usize,
    );
    assert_eq!(from, job.lines[first].source_line, "{doubt}");
    let last = *journal.unconfirmed.last().unwrap();
    assert!(to >= job.lines[last].source_line, "{doubt}");
    assert!(
        doubt["reason"].as_str().unwrap().contains("restarted"),
        "{doubt}"
    );
    // Nothing ran: the refusal moved nothing.
    let before = get(a, "/api/devices/sim").json()["motions"]
        .as_array()
        .unwrap()
        .len();
    assert_eq!(before, 0);
    // The operator looks at the work and continues from the first line in doubt (what may
    // have been cut is cut again; nothing is skipped).
    let r = send(
        a,
        "POST",
        "/api/jobs",
        &json!({"sheet": 1, "resume_from": from}),
    );
    assert_eq!(r.status, 201, "{}", String::from_utf8_lossy(&r.body));
    let asked = job_until(a, 2, "asked", |j| !j["question"].is_null());
    let r = send(
        a,
        "POST",
        "/api/jobs/2/answer",
        &json!({"question": asked["question"]["id"], "yes": true}),
    );
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    let done = job_until(a, 2, "ended", |j| {
        ["done", "failed", "stopped"].contains(&j["state"].as_str().unwrap())
    });
    assert_eq!(done["state"], "done", "{done}");
    assert_eq!(done["report"]["previously_done"], first);
    assert!(done["in_doubt"].is_null(), "{done}");
    let sim = get(a, "/api/devices/sim").json();
    assert_runs_from(sim["motions"].as_array().unwrap(), &job, first);
    assert!(flatcut_grbl::Journal::read(&journal_path).unwrap().finished);
    srv.stop().unwrap();
}

/// Checks that a simulator's trace `sim` is the whole of `job`: its motions, each once, in order.
fn assert_ran_whole_job(sim: &[flatcut_firmware_sim::TraceSegment], job: &flatcut_grbl::Job) {
    let ran = flatcut_testkit::trace::joined(sim);
    let want = motions_before(job, job.len());
    assert_eq!(ran.len(), want.len(), "motions of a whole job");
    for (k, (text, to)) in want.iter().enumerate() {
        assert_eq!(&ran[k].text, text, "motion {k}");
        assert!(
            near(ran[k].to, *to),
            "motion {k}: ran to {:?}, the job {to:?}",
            ran[k].to
        );
    }
}

/// Checks that a simulator's trace `sim` is job `job` stopped where its journal says: every line
/// before the one it stopped in (`P`), each once, that one up to where the journal says, and
/// nothing after (or, stopped between lines, the lines it marks done and nothing after); the
/// tool off in its stop record.
fn assert_stopped_as_journal_says(
    sim: &[flatcut_firmware_sim::TraceSegment],
    job: &flatcut_grbl::Job,
    journal: &Path,
) {
    use flatcut_testkit::trace::joined;
    let journal = flatcut_grbl::Journal::read(journal).unwrap();
    assert!(!journal.finished);
    let stop = journal.stop.expect("a stop record");
    assert!(stop.modal.contains("M5"), "{}", stop.modal);
    // Stopped between two lines (the device had run every line sent and waited for the next,
    // as it does when the sender lags on a loaded machine), the journal names no line part-way:
    // the lines it marks done ran whole, each once, and nothing after them.
    let (part, at) = journal.partial.unwrap_or_else(|| {
        let part = journal.done.iter().take_while(|&&d| d).count();
        (part, stop.machine)
    });
    assert!(!journal.done[part..].iter().any(|&d| d));
    let want = motions_before(job, part);
    let ran = joined(sim);
    // The line stopped in may not have moved yet (or moves nothing: a dwell, a tool command).
    let cut = journal.partial.is_some() && ran.len() > want.len();
    assert_eq!(ran.len(), want.len() + usize::from(cut), "motions executed");
    for (k, (text, to)) in want.iter().enumerate() {
        assert_eq!(&ran[k].text, text, "motion {k}");
        assert!(
            near(ran[k].to, *to),
            "motion {k}: ran to {:?}, the job {to:?}",
            ran[k].to
        );
    }
    let end = ran.last().unwrap();
    if cut {
        assert_eq!(end.text, job.lines[part].text);
    }
    assert!(near(end.to, at), "{end:?} against {at:?}");
    assert_eq!(stop.machine, end.to);
}

/// Two devices open at once (the embedded simulator and a second one, `simulator:2`), each with
/// its own job: both stream at the same time, the pages hear each job's events tagged with its
/// device; a third job on a busy device is refused; a stop on the first leaves the second
/// running to its end. Each simulator executed its own job: the second every motion once, in
/// order; the first exactly the lines before the one its journal says it stopped in. Each device
/// keeps its own journal of the same sheet. (Two jobs at 200× real time on 1 Mbaud links.)
#[test]
fn serve_runs_jobs_on_two_devices_at_once_and_a_stop_on_one_leaves_the_other() {
    let dir = lampshade();
    let srv = serve(&dir.path().join("project.toml"));
    let app = srv.app.clone();
    let a = srv.addr();
    let gcode = get(a, "/api/job.gcode").body;
    let job = flatcut_grbl::Job::parse(std::str::from_utf8(&gcode).unwrap()).unwrap();
    for id in ["simulator", "simulator:2"] {
        let c = send(
            a,
            "POST",
            "/api/devices/connect",
            &json!({"device": id, "speed": 200, "baud": 1_000_000}),
        );
        assert_eq!(c.status, 200, "{}", String::from_utf8_lossy(&c.body));
        assert_eq!(c.json()["id"], id);
    }
    let bad = send(
        a,
        "POST",
        "/api/devices/connect",
        &json!({"device": "simulator:a b"}),
    );
    assert_eq!(bad.status, 400, "{}", String::from_utf8_lossy(&bad.body));
    let d = get(a, "/api/devices").json();
    let opened: Vec<&str> = d["opened"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["id"].as_str().unwrap())
        .collect();
    assert_eq!(opened, ["simulator", "simulator:2"], "{d}");
    assert_eq!(d["default"], "simulator:2");
    assert_eq!(d["open"]["id"], "simulator:2");
    for id in ["simulator", "simulator:2"] {
        let listed = d["devices"]
            .as_array()
            .unwrap()
            .iter()
            .find(|x| x["id"] == id);
        assert_eq!(listed.map(|x| &x["open"]), Some(&json!(true)), "{d}");
    }
    // The pages' events, from before the jobs start.
    let mut s = TcpStream::connect(a).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    write!(
        s,
        "GET /api/events HTTP/1.1\r\nHost: localhost:{}\r\n\r\n",
        a.port()
    )
    .unwrap();
    let mut events = BufReader::new(s);
    // One job named to the first device, one to the default device (the second).
    let one = send(a, "POST", "/api/jobs", &json!({"device": "simulator"}));
    assert_eq!(one.status, 201, "{}", String::from_utf8_lossy(&one.body));
    let two = send(a, "POST", "/api/jobs", &json!({"sheet": 1}));
    assert_eq!(two.status, 201, "{}", String::from_utf8_lossy(&two.body));
    let (one, two) = (one.json(), two.json());
    assert_eq!(
        (one["device_id"].as_str(), two["device_id"].as_str()),
        (Some("simulator"), Some("simulator:2"))
    );
    assert!(
        one["journal"]
            .as_str()
            .unwrap()
            .ends_with("/job-1.gcode.journal"),
        "{one}"
    );
    assert!(
        two["journal"]
            .as_str()
            .unwrap()
            .ends_with("/job-1.gcode@simulator-2.journal"),
        "{two}"
    );
    let third = send(a, "POST", "/api/jobs", &json!({"device": "simulator"}));
    assert_eq!(
        third.status,
        409,
        "{}",
        String::from_utf8_lossy(&third.body)
    );
    // Both run at once.
    job_until(a, 1, "ran 300 lines", |j| lines_done(j) > 300);
    let both = job_until(a, 2, "ran 300 lines", |j| lines_done(j) > 300);
    assert_eq!(both["state"], "running");
    assert_eq!(get(a, "/api/jobs/1").json()["state"], "running");
    let d = get(a, "/api/devices").json();
    assert_eq!(d["running"].as_array().unwrap().len(), 2, "{d}");
    assert!(
        d["opened"]
            .as_array()
            .unwrap()
            .iter()
            .all(|o| o["busy"] == true),
        "{d}"
    );
    // Each job's progress reached the pages tagged with its device.
    let mut seen = String::new();
    while !(seen.contains("\"device_id\":\"simulator\"")
        && seen.contains("\"device_id\":\"simulator:2\""))
    {
        let mut l = String::new();
        assert!(
            events.read_line(&mut l).unwrap() > 0,
            "the events ended: {seen}"
        );
        if l.starts_with("data:") && l.contains("\"lines_done\"") {
            seen.push_str(&l);
        }
    }
    // A stop on the first leaves the second running to its end.
    job_until(a, 1, "reached the outlines", |j| lines_done(j) > CUT_LAYER);
    assert_eq!(send(a, "POST", "/api/jobs/1/stop", &json!({})).status, 200);
    let stopped = job_until(a, 1, "stopped", |j| j["state"] == "stopped");
    assert!(
        stopped["message"].as_str().unwrap().contains("tool off"),
        "{stopped}"
    );
    let on = get(a, "/api/jobs/2").json();
    assert!(
        ["running", "done"].contains(&on["state"].as_str().unwrap()),
        "the second job after the first stopped: {on}"
    );
    let done = job_until(a, 2, "ended", |j| {
        ["done", "failed", "stopped"].contains(&j["state"].as_str().unwrap())
    });
    assert_eq!(done["state"], "done", "{done}");
    assert_eq!(
        done["progress"]["lines_done"],
        done["progress"]["lines_total"]
    );
    // What each simulator executed.
    for id in ["simulator:2", "simulator"] {
        let c = send(a, "POST", "/api/devices/close", &json!({"device": id}));
        assert_eq!(c.json()["closed"], id);
    }
    assert_eq!(get(a, "/api/devices").json()["opened"], json!([]));
    assert_ran_whole_job(&app.devices.last_sim_of("simulator:2").unwrap().trace, &job);
    let first = app.devices.last_sim_of("simulator").unwrap().trace;
    assert_stopped_as_journal_says(&first, &job, &dir.path().join("job-1.gcode.journal"));
    let journal2 =
        flatcut_grbl::Journal::read(dir.path().join("job-1.gcode@simulator-2.journal")).unwrap();
    assert!(journal2.finished);
    srv.stop().unwrap();
}

/// The pen-down segments of an HP-GL job (mm), read here from its text (absolute and relative
/// moves, `PU`/`PD`, `SP`/`IN` lifting the pen), independently of the writer and the plotter.
fn hpgl_strokes(text: &str) -> Vec<([f64; 2], [f64; 2])> {
    let (mut pos, mut down, mut rel) = ([0.0f64; 2], false, false);
    let mut out = Vec::new();
    for instr in text.split(';') {
        let instr = instr.trim();
        if instr.len() < 2 {
            continue;
        }
        let (op, args) = instr.split_at(2);
        let nums: Vec<f64> = args
            .split([',', ' '])
            .filter(|t| !t.is_empty())
            .map(|t| t.parse().unwrap())
            .collect();
        match op {
            "PU" | "SP" | "IN" => down = false,
            "PD" => down = true,
            "PA" => rel = false,
            "PR" => rel = true,
            _ => continue,
        }
        if !matches!(op, "PU" | "PD" | "PA" | "PR") {
            continue;
        }
        for p in nums.chunks_exact(2) {
            let to = match rel {
                true => [pos[0] + p[0] / 40.0, pos[1] + p[1] / 40.0],
                false => [p[0] / 40.0, p[1] / 40.0],
            };
            if down && to != pos {
                out.push((pos, to));
            }
            pos = to;
        }
    }
    out
}

/// The embedded plotter's pen strokes (`GET /api/devices/sim?device=plotter-sim`) once it has
/// drawn everything it received, and whether its pen is down.
fn plotter_drained(a: SocketAddr) -> (Vec<([f64; 2], [f64; 2])>, bool) {
    let t0 = std::time::Instant::now();
    loop {
        let s = get(a, "/api/devices/sim?device=plotter-sim").json();
        if s["idle"] == true {
            let xy = |v: &Value| [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()];
            let strokes = s["strokes"]
                .as_array()
                .unwrap()
                .iter()
                .map(|k| (xy(&k["from"]), xy(&k["to"])))
                .collect();
            assert_eq!(s["bytes_lost"], 0, "{}", s["bytes_lost"]);
            return (strokes, s["pen_down"] == true);
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "the plotter never idled"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn bytes_sent(j: &Value) -> u64 {
    j["progress"]["bytes_sent"].as_u64().unwrap_or(0)
}

/// An HP-GL plotter in the device panel: the embedded HP-GL plotter (`plotter-sim`, opened with a
/// pen plotter profile for the lampshade's A0 sheet) takes `POST /api/jobs` as the sheet's HP-GL
/// (`GET /api/job.plt`'s bytes for that profile). Followed on `/api/events` to its end, its
/// progress is the bytes sent and says so; paused, the feed stops at an instruction's end and the
/// plotter's pen is up (nothing drawn until the resume); resumed, the job ends and the plotter
/// drew the job's pen-down moves, each once, in order. A second job stopped part-way: the
/// plotter drew the job's beginning and nothing after the stop. GRBL's commands are refused.
#[test]
fn serve_plots_hpgl_on_the_embedded_plotter_with_pause_pen_up_and_stop() {
    let dir = lampshade();
    let profile = std::fs::read_to_string(root().join("crates/gcode/profiles/pen-hpgl.toml"))
        .unwrap()
        .replace(
            "work_area_mm = [400.0, 270.0]",
            "work_area_mm = [1200.0, 920.0]",
        );
    let prof = dir.path().join("pen-a0.toml");
    std::fs::write(&prof, profile).unwrap();
    let prof = prof.to_str().unwrap().to_string();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    // Every event the server sends, read until it stops.
    let mut s = TcpStream::connect(a).unwrap();
    write!(
        s,
        "GET /api/events HTTP/1.1\r\nHost: localhost:{}\r\n\r\n",
        a.port()
    )
    .unwrap();
    let follow = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = BufReader::new(s).read_to_string(&mut text);
        text
    });
    let d = get(a, "/api/devices").json();
    let listed = d["devices"].as_array().unwrap();
    assert!(
        listed
            .iter()
            .any(|x| x["id"] == "plotter-sim" && x["protocol"] == "hpgl"),
        "{d}"
    );
    let c = send(
        a,
        "POST",
        "/api/devices/connect",
        &json!({"device": "plotter-sim", "profile": prof, "speed": 100, "baud": 115_200}),
    );
    assert_eq!(c.status, 200, "{}", String::from_utf8_lossy(&c.body));
    let c = c.json();
    assert_eq!(c["protocol"], "hpgl", "{c}");
    assert_eq!(c["plotter"]["flow_control"], "xon-xoff", "{c}");
    let home = send(
        a,
        "POST",
        "/api/devices/home",
        &json!({"device": "plotter-sim"}),
    );
    assert_eq!(home.status, 409);
    assert!(String::from_utf8_lossy(&home.body).contains("HP-GL plotter"));
    let plt = get(a, &format!("/api/job.plt?profile={prof}"));
    assert_eq!(plt.status, 200);
    let want = hpgl_strokes(std::str::from_utf8(&plt.body).unwrap());
    assert!(want.len() > 100, "{} strokes", want.len());
    let total = plt.body.len() as u64;
    // A job, paused a third of the way and resumed.
    let r = send(a, "POST", "/api/jobs", &json!({"device": "plotter-sim"}));
    assert_eq!(r.status, 201, "{}", String::from_utf8_lossy(&r.body));
    let j = r.json();
    assert_eq!(
        (j["id"].as_u64(), j["protocol"].as_str()),
        (Some(1), Some("hpgl"))
    );
    assert!(j["journal"].is_null());
    assert_eq!(send(a, "POST", "/api/jobs", &json!({})).status, 409);
    job_until(a, 1, "sent a third", |j| bytes_sent(j) > total / 3);
    assert_eq!(send(a, "POST", "/api/jobs/1/hold", &json!({})).status, 200);
    let held = job_until(a, 1, "paused", |j| {
        j["state"] == "held" && j["progress"]["paused"] == true
    });
    assert_eq!(held["progress"]["progress_basis"], "bytes_sent");
    let at = bytes_sent(&held) as usize;
    assert_eq!(plt.body[at - 1], b';', "paused inside an instruction");
    let (paused, pen_down) = plotter_drained(a);
    assert!(!pen_down, "the pen is up while paused");
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        plotter_drained(a).0.len(),
        paused.len(),
        "drawn while paused"
    );
    assert_eq!(bytes_sent(&get(a, "/api/jobs/1").json()) as usize, at);
    assert_eq!(
        send(a, "POST", "/api/jobs/1/resume", &json!({})).status,
        200
    );
    let done = job_until(a, 1, "ended", |j| {
        ["done", "failed", "stopped"].contains(&j["state"].as_str().unwrap())
    });
    assert_eq!(done["state"], "done", "{done}");
    assert_eq!(done["report"]["bytes_sent"].as_u64(), Some(total));
    assert_eq!(done["report"]["pauses"], 1);
    let (drawn, pen_down) = plotter_drained(a);
    assert!(!pen_down);
    assert_eq!(drawn.len(), want.len(), "strokes drawn and in the job");
    for (k, (got, exp)) in drawn.iter().zip(&want).enumerate() {
        let far = (0..2)
            .map(|i| (got.0[i] - exp.0[i]).abs().max((got.1[i] - exp.1[i]).abs()))
            .fold(0.0f64, f64::max);
        assert!(far < 1e-9, "stroke {k}: {got:?} vs {exp:?}");
    }
    // A second job, stopped part-way: the beginning of the job drawn, nothing after the stop.
    assert_eq!(send(a, "POST", "/api/jobs", &json!({})).status, 201);
    job_until(a, 2, "sent a quarter", |j| bytes_sent(j) > total / 4);
    assert_eq!(send(a, "POST", "/api/jobs/2/stop", &json!({})).status, 200);
    let stopped = job_until(a, 2, "ended", |j| j["state"] == "stopped");
    assert!(
        stopped["message"].as_str().unwrap().contains("aborted"),
        "{stopped}"
    );
    let (after, pen_down) = plotter_drained(a);
    assert!(!pen_down);
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(
        plotter_drained(a).0.len(),
        after.len(),
        "drawn after the stop"
    );
    let second = &after[drawn.len()..];
    assert!(
        !second.is_empty() && second.len() < want.len(),
        "{} of {} strokes",
        second.len(),
        want.len()
    );
    assert_eq!(second, &want[..second.len()]);
    srv.stop().unwrap();
    // Every page heard the plot: progress in bytes sent, growing, to the end of job 1.
    let text = follow.join().unwrap();
    let jobs: Vec<Value> = text
        .split("event: job\ndata: ")
        .skip(1)
        .map(|t| serde_json::from_str(t.lines().next().unwrap()).unwrap())
        .filter(|j: &Value| j["id"] == 1)
        .collect();
    let sent: Vec<u64> = jobs.iter().map(bytes_sent).collect();
    assert!(sent.len() > 3, "{} job events", sent.len());
    assert!(sent.windows(2).all(|w| w[0] <= w[1]), "{sent:?}");
    assert_eq!(jobs.last().unwrap()["state"], "done");
    assert!(jobs.iter().any(|j| j["state"] == "held"));
}
