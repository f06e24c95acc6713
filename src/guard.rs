//! A last line of defence around the third-party decoders raylab calls on
//! files from strangers (PNG, JPEG, EXR, glTF's JSON, TOML).
//!
//! Those crates are meant never to panic on bad input, but fuzzing found one
//! that does (`png` 0.18.1 on a short palette chunk, which raylab now checks
//! for first). [`catch`] turns such a panic into an error message, so a file
//! that trips a decoder bug still gets one line and a non-zero exit instead
//! of a crash. [`quiet`] tells a panic hook (the `raylab` binary installs
//! one) not to print the usual multi-line report for a panic that is caught
//! here. The fuzz targets still see every such panic (libFuzzer's panic hook
//! aborts before unwinding), so decoder bugs are found and worked around.
//!
//! Messages about such files stay one readable line: [`one_line`] escapes the
//! control characters of a name, [`quote`] cuts a long word short.

use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};

thread_local! {
    static GUARDED: Cell<bool> = const { Cell::new(false) };
}

/// Starts the message of an error made from a caught decoder panic.
pub const DECODER_PANIC: &str = "the decoder failed on this file (an internal error of the";

/// Runs `f` (a call into the decoder named `decoder`, e.g. `"png"`), turning a
/// panic inside it into `Err` with a one-line message that names the decoder.
pub fn catch<T>(decoder: &str, f: impl FnOnce() -> T) -> Result<T, String> {
    let before = GUARDED.with(|g| g.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    GUARDED.with(|g| g.set(before));
    result.map_err(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        let what = what.lines().next().unwrap_or("").to_string();
        format!("{DECODER_PANIC} {decoder} crate: {what})")
    })
}

/// Whether this thread is inside [`catch`]: a panic hook should then stay
/// quiet, since the panic becomes an ordinary error.
pub fn quiet() -> bool {
    GUARDED.with(|g| g.get())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_one_line_naming_the_decoder() {
        let hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let r: Result<(), String> = catch("png", || panic!("range end index 3\nmore"));
        std::panic::set_hook(hook);
        let e = r.unwrap_err();
        assert!(
            e.starts_with(DECODER_PANIC) && e.contains("png crate: range end index 3"),
            "{e}"
        );
        assert!(!e.contains('\n'));
        assert!(!quiet(), "the flag is reset after the panic");
        assert_eq!(catch("png", || 7), Ok(7));
    }
}

/// `message` as one printable line: control characters (a newline in a file
/// name, say) become escapes such as `\n`, so that an error or warning is
/// always one line however odd the names it quotes.
pub fn one_line(message: &str) -> std::borrow::Cow<'_, str> {
    if !message.chars().any(char::is_control) {
        return message.into();
    }
    message
        .chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect::<String>()
        .into()
}

/// Longest word quoted in a message, in characters: a malformed file may
/// hold a 100 MB token, and the message must stay one readable line.
pub const QUOTE_CHARS: usize = 40;

/// `word` for an error message: cut to [`QUOTE_CHARS`] characters (with `…`
/// and the full length) when longer.
pub fn quote(word: &str) -> String {
    match word.char_indices().nth(QUOTE_CHARS) {
        None => word.to_string(),
        Some((cut, _)) => format!("{}… ({} bytes)", &word[..cut], word.len()),
    }
}

#[cfg(test)]
mod one_line_tests {
    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(super::one_line("a\nb\tc\u{c}"), "a\\nb\\tc\\u{c}");
        assert_eq!(super::one_line("plain é"), "plain é");
    }
}
