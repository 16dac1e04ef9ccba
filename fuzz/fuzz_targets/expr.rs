//! Any text given to the expression parser gives `Ok` or `Err` quickly, never a panic, a
//! stack overflow or a hang; an `Ok` expression evaluates to a number (or NaN) anywhere,
//! also on a thread with the 2 MB stack of the solver's worker threads.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sgbem::input::expr::{Expr, MAX_LEN};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let text = text.to_string();
    let result = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || match Expr::parse(&text) {
            Ok(e) => {
                assert!(text.chars().count() <= MAX_LEN);
                for p in [[0.0, 0.0], [0.3, -1.7], [1e9, -1e9], [f64::MIN_POSITIVE, 1.0]] {
                    let v = e.eval(p);
                    assert!(v.is_finite() || v.is_nan() || v.is_infinite());
                }
            }
            Err(m) => assert!(!m.is_empty()),
        })
        .expect("thread")
        .join();
    assert!(result.is_ok(), "the parser or the evaluator panicked");
});
