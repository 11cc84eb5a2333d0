//! The server's answers: bytes with a status and type, errors as one-line JSON.

/// An answer before it is written: status, content type, body and extra headers.
pub(crate) struct Reply {
    pub status: u16,
    pub content_type: &'static str,
    pub body: Vec<u8>,
    pub headers: Vec<(&'static str, String)>,
}

impl Reply {
    pub fn bytes(status: u16, content_type: &'static str, body: Vec<u8>) -> Reply {
        Reply {
            status,
            content_type,
            body,
            headers: Vec::new(),
        }
    }

    pub fn json(value: &serde_json::Value) -> Reply {
        Reply::bytes(200, "application/json", value.to_string().into_bytes())
    }

    /// Little-endian binary data.
    pub fn binary(body: Vec<u8>) -> Reply {
        Reply::bytes(200, "application/octet-stream", body)
    }

    /// `{"error": message}` with status `status`.
    pub fn error(status: u16, message: impl std::fmt::Display) -> Reply {
        let body = serde_json::json!({ "error": message.to_string() });
        Reply::bytes(status, "application/json", body.to_string().into_bytes())
    }

    pub fn with_header(mut self, name: &'static str, value: String) -> Reply {
        self.headers.push((name, value));
        self
    }

    /// Every header to send besides the framing ones: type, the fixed safety headers, extras.
    pub fn all_headers(&self) -> impl Iterator<Item = (&str, &str)> {
        let fixed = [
            ("Content-Type", self.content_type),
            ("Cache-Control", "no-store"),
            ("X-Content-Type-Options", "nosniff"),
            // The page's URL carries the token: never send it on.
            ("Referrer-Policy", "no-referrer"),
            (
                "Content-Security-Policy",
                "default-src 'self'; style-src 'self' 'unsafe-inline'; frame-ancestors 'none'",
            ),
        ];
        fixed
            .into_iter()
            .chain(self.headers.iter().map(|(k, v)| (*k, v.as_str())))
    }
}
