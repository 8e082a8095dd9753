//! Who may talk to the workbench. By default it listens on the loopback addresses only; a page
//! of another site open in the same browser still reaches loopback, so every request's `Host`
//! must name this server (a DNS-rebinding page's host does not). Listening on another address
//! (`--bind`) needs the token printed at start with every request: an `Authorization: Bearer`
//! header, an `X-Flatcut-Token` header, a `token` query parameter (how the printed URL carries
//! it; the page then keeps it in a same-site cookie), or that cookie.

use std::net::IpAddr;

use axum::extract::{Request, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

/// The cookie the page keeps the token in.
pub const TOKEN_COOKIE: &str = "flatcut_token";

/// The access rules of one server.
#[derive(Clone, Debug)]
pub struct Guard {
    /// Host names (without port) a request may name.
    pub hosts: Vec<String>,
    /// The port the server listens on (a `Host` with another port is refused).
    pub port: u16,
    /// The token every request must carry, when listening beyond loopback.
    pub token: Option<String>,
}

impl Guard {
    /// Whether the `Host` header names this server: one of its host names at its port (or
    /// without a port).
    pub fn host_ok(&self, host: &str) -> bool {
        let (name, port) = split_host(host);
        let port_ok = port.is_none_or(|p| p == self.port);
        port_ok && self.hosts.iter().any(|h| h.eq_ignore_ascii_case(name))
    }

    /// Whether the request carries the token (always, when none is needed).
    pub fn token_ok(&self, headers: &HeaderMap, query: Option<&str>) -> bool {
        let Some(want) = &self.token else {
            return true;
        };
        let eq = |got: &str| constant_time_eq(got.as_bytes(), want.as_bytes());
        let bearer = headers
            .get(header::AUTHORIZATION)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "));
        let custom = headers.get("x-flatcut-token").and_then(|v| v.to_str().ok());
        let cookie = cookie_token(headers);
        let query = query_token(query);
        [bearer, custom, cookie.as_deref(), query.as_deref()]
            .into_iter()
            .flatten()
            .any(eq)
    }
}

/// The host names a server bound to `addr` answers to: the loopback names for a loopback
/// address; for another address that address, and this machine's name.
pub fn hosts_for(addr: IpAddr, bound_beyond_loopback: bool) -> Vec<String> {
    let mut hosts = vec![
        "localhost".to_string(),
        "127.0.0.1".to_string(),
        "[::1]".to_string(),
    ];
    if bound_beyond_loopback {
        hosts.push(match addr {
            IpAddr::V4(a) => a.to_string(),
            IpAddr::V6(a) => format!("[{a}]"),
        });
        if let Ok(name) = std::fs::read_to_string("/proc/sys/kernel/hostname") {
            let name = name.trim();
            if !name.is_empty() {
                hosts.push(name.to_string());
            }
        }
    }
    hosts
}

/// `name:port`, `[v6]:port` or a bare name.
fn split_host(host: &str) -> (&str, Option<u16>) {
    if host.starts_with('[') {
        return match host.find(']') {
            Some(i) => {
                let port = host[i + 1..].strip_prefix(':').and_then(|p| p.parse().ok());
                (&host[..=i], port)
            }
            None => (host, None),
        };
    }
    match host.rsplit_once(':') {
        Some((name, port)) => (name, port.parse().ok().or(Some(0))),
        None => (host, None),
    }
}

fn cookie_token(headers: &HeaderMap) -> Option<String> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|kv| kv.trim().split_once('='))
        .find(|(k, _)| *k == TOKEN_COOKIE)
        .map(|(_, v)| v.to_string())
}

fn query_token(query: Option<&str>) -> Option<String> {
    query?
        .split('&')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == "token")
        .map(|(_, v)| v.to_string())
}

/// Compares two byte strings in time independent of where they differ.
fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// The middleware: a request naming another host gets 421, one without the token 401; a page
/// load carrying the token in its query gets it as a cookie.
pub async fn check(State(guard): State<Guard>, req: Request, next: Next) -> Response {
    let host = req
        .headers()
        .get(header::HOST)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    if !guard.host_ok(host) {
        return (
            StatusCode::MISDIRECTED_REQUEST,
            axum::Json(serde_json::json!({
                "error": format!("Host '{host}' is not this workbench (DNS rebinding is refused); open it at the address it printed")
            })),
        )
            .into_response();
    }
    let query = req.uri().query().map(str::to_string);
    if !guard.token_ok(req.headers(), query.as_deref()) {
        return (
            StatusCode::UNAUTHORIZED,
            axum::Json(serde_json::json!({
                "error": "this workbench listens beyond this machine: send the token it printed at start (Authorization: Bearer TOKEN, or ?token=TOKEN)"
            })),
        )
            .into_response();
    }
    let set_cookie = guard
        .token
        .as_ref()
        .filter(|_| query_token(query.as_deref()).is_some());
    let mut resp = next.run(req).await;
    if let Some(t) = set_cookie
        && let Ok(v) = HeaderValue::from_str(&format!(
            "{TOKEN_COOKIE}={t}; Path=/; HttpOnly; SameSite=Strict"
        ))
    {
        resp.headers_mut().insert(header::SET_COOKIE, v);
    }
    resp
}

#[cfg(test)]
mod tests {
    use super::*;

    fn guard(token: Option<&str>) -> Guard {
        Guard {
            hosts: hosts_for(IpAddr::from([127, 0, 0, 1]), false),
            port: 8080,
            token: token.map(str::to_string),
        }
    }

    #[test]
    fn only_this_servers_names_and_port_are_accepted() {
        let g = guard(None);
        for ok in [
            "localhost:8080",
            "127.0.0.1:8080",
            "[::1]:8080",
            "LOCALHOST",
            "localhost",
        ] {
            assert!(g.host_ok(ok), "{ok}");
        }
        for bad in [
            "evil.example:8080",
            "localhost:8081",
            "127.0.0.1:80",
            "localhost.evil.example:8080",
            "",
            "localhost:x",
            "[::2]:8080",
        ] {
            assert!(!g.host_ok(bad), "{bad}");
        }
    }

    #[test]
    fn the_token_is_taken_from_a_header_the_query_or_the_cookie() {
        let g = guard(Some("s3cret"));
        let mut h = HeaderMap::new();
        assert!(!g.token_ok(&h, None));
        assert!(!g.token_ok(&h, Some("token=wrong")));
        assert!(g.token_ok(&h, Some("a=1&token=s3cret")));
        h.insert(
            header::AUTHORIZATION,
            HeaderValue::from_static("Bearer s3cret"),
        );
        assert!(g.token_ok(&h, None));
        let mut h = HeaderMap::new();
        h.insert(
            header::COOKIE,
            HeaderValue::from_static("x=1; flatcut_token=s3cret"),
        );
        assert!(g.token_ok(&h, None));
        let mut h = HeaderMap::new();
        h.insert("x-flatcut-token", HeaderValue::from_static("s3cre"));
        assert!(!g.token_ok(&h, None));
        assert!(guard(None).token_ok(&HeaderMap::new(), None));
    }
}
