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
/// flattening has five pieces in each of the shoe's three sizes and a new mating seam per size,
/// within the leather's limits; undo brings the four pieces back and redo the five; a loose line
/// is refused with the loader's message.
#[test]
fn serve_a_line_across_the_vamp_makes_a_fifth_piece() {
    let dir = shoe();
    let srv = serve(&dir.path().join("project.toml"));
    let a = srv.addr();
    let f = send(a, "POST", "/api/flatten", &json!({}));
    assert_eq!(f.status, 200, "{}", String::from_utf8_lossy(&f.body));
    let f = f.json();
    assert_eq!(f["pieces"].as_array().unwrap().len(), 4 * SHOE_SIZES);
    assert_eq!(f["pieces"][0]["name"], "toe cap 40");
    assert_eq!(f["pieces"][0]["part"], "upper");
    assert_eq!(f["pieces"][0]["size"], "40");
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
    let f = send(a, "POST", "/api/flatten", &json!({})).json();
    let pieces = f["pieces"].as_array().unwrap();
    assert_eq!(pieces.len(), 5 * SHOE_SIZES);
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
        4 * SHOE_SIZES
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
