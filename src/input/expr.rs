//! Prescribed values: a number, or an expression in `x`, `y` and the pseudo-time `t`.
//!
//! Place in the flow: used by `scene` (parsing and validation) and later stages (evaluation
//! at nodes and quadrature points). Expressions are parsed once by the `evalexpr` crate and
//! evaluated through a small context of our own that knows exactly `x`, `y`, `t`, `pi` and the
//! functions docs/scene.md §9 lists (`sqrt sin cos tan asin acos atan atan2 exp ln abs min max floor
//! ceil`), so any other name is refused when the scene is read, not in the middle of a solve.
//! Messages are the tool's own: the evaluator's internal names never reach the user.
//!
//! Integer literals are read as floating-point numbers: `"1/2*x"` means 0.5·x, as an engineer
//! would expect, not integer division.

use crate::error::did_you_mean;
use evalexpr::{
    build_operator_tree, Context, DefaultNumericTypes, EvalexprError, EvalexprResult, Node, Value,
};

/// Functions an expression may call, with their number of arguments.
pub(crate) const FUNCTIONS: [(&str, usize); 15] = [
    ("sqrt", 1),
    ("sin", 1),
    ("cos", 1),
    ("tan", 1),
    ("asin", 1),
    ("acos", 1),
    ("atan", 1),
    ("floor", 1),
    ("ceil", 1),
    ("exp", 1),
    ("ln", 1),
    ("abs", 1),
    ("atan2", 2),
    ("min", 2),
    ("max", 2),
];

/// Variables an expression may read.
pub(crate) const VARIABLES: [&str; 4] = ["x", "y", "t", "pi"];

/// A prescribed scalar: constant or a function of the point (x, y) and the pseudo-time t.
#[derive(Debug, Clone)]
pub enum Scalar {
    Const(f64),
    Expr(Expr),
}

impl Scalar {
    /// Value at the point p and pseudo-time t.
    pub fn eval(&self, p: [f64; 2], t: f64) -> f64 {
        match self {
            Scalar::Const(v) => *v,
            Scalar::Expr(e) => e.eval(p, t),
        }
    }

    /// True when the value depends on the pseudo-time `t`.
    pub(crate) fn uses_time(&self) -> bool {
        matches!(self, Scalar::Expr(e) if e.reads("t"))
    }

    /// True when the value depends on the point (`x` or `y`).
    pub(crate) fn uses_space(&self) -> bool {
        matches!(self, Scalar::Expr(e) if e.reads("x") || e.reads("y"))
    }

    /// The constant value, if the value does not depend on the point.
    pub(crate) fn as_const(&self) -> Option<f64> {
        match self {
            Scalar::Const(v) => Some(*v),
            Scalar::Expr(_) => None,
        }
    }

    /// True when the value is the constant 0.
    pub(crate) fn is_zero(&self) -> bool {
        self.as_const() == Some(0.0)
    }
}

impl std::fmt::Display for Scalar {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Scalar::Const(v) => write!(f, "{v}"),
            Scalar::Expr(e) => write!(f, "\"{}\"", e.text),
        }
    }
}

/// A parsed expression in `x`, `y` and `t`.
#[derive(Debug, Clone)]
pub struct Expr {
    pub text: String,
    tree: Node<DefaultNumericTypes>,
}

impl Expr {
    /// Parses and checks an expression; the error message says what is wrong with it.
    pub fn parse(text: &str) -> Result<Expr, String> {
        if text.trim().is_empty() {
            return Err("the expression is empty".into());
        }
        if let Some(c) = text
            .chars()
            .find(|c| matches!(c, '=' | ';' | '"' | '&' | '|' | '!'))
        {
            return Err(format!(
                "`{c}` is not allowed: an expression is arithmetic in x, y and t \
                 (+ - * / ^, parentheses, {}, pi)",
                function_list()
            ));
        }
        check_size(text)?;
        let tree = build_operator_tree::<DefaultNumericTypes>(&floats_for_integers(text))
            .map_err(|e| format!("it does not parse: {}", problem(&e)))?;
        let depth = tree_depth(&tree);
        if depth > MAX_TREE_DEPTH {
            return Err(format!(
                "it nests {depth} operations deep, more than {MAX_TREE_DEPTH}: simplify it \
                 (e.g. a long sum as a product, a polynomial in Horner form)"
            ));
        }
        for name in tree.iter_read_variable_identifiers() {
            if !VARIABLES.contains(&name) {
                return Err(format!(
                    "unknown name `{name}`: an expression may use x, y, t (pseudo-time) and pi{}",
                    did_you_mean(name, VARIABLES.iter().copied())
                ));
            }
        }
        for name in tree.iter_function_identifiers() {
            if !FUNCTIONS.iter().any(|(f, _)| *f == name) {
                return Err(format!(
                    "unknown function `{name}`: use one of {}{}",
                    function_list(),
                    did_you_mean(name, FUNCTIONS.iter().map(|(f, _)| *f))
                ));
            }
        }
        let expr = Expr {
            text: text.to_string(),
            tree,
        };
        // Evaluate once: wrong argument counts and non-numeric results show up here.
        expr.try_eval([0.25, 0.75], 1.0)?;
        Ok(expr)
    }

    /// Whether the expression reads the variable `name`.
    pub fn reads(&self, name: &str) -> bool {
        self.tree
            .iter_read_variable_identifiers()
            .any(|v| v == name)
    }

    /// Value at p and pseudo-time t; NaN where the expression is undefined (the caller
    /// checks finiteness).
    pub fn eval(&self, p: [f64; 2], t: f64) -> f64 {
        self.try_eval(p, t).unwrap_or(f64::NAN)
    }

    fn try_eval(&self, p: [f64; 2], t: f64) -> Result<f64, String> {
        let ctx = PointContext {
            x: Value::Float(p[0]),
            y: Value::Float(p[1]),
            t: Value::Float(t),
            pi: Value::Float(std::f64::consts::PI),
        };
        match self.tree.eval_with_context(&ctx) {
            Ok(Value::Float(v)) => Ok(v),
            Ok(Value::Int(v)) => Ok(v as f64),
            Ok(Value::Tuple(v)) => Err(format!(
                "it gives {} values separated by commas, not one number: a comma belongs \
                 only between the arguments of atan2, min or max",
                v.len()
            )),
            Ok(Value::Empty) => Err("it gives no value (empty parentheses?)".into()),
            Ok(_) => Err("it does not give a number".into()),
            Err(EvalexprError::CustomMessage(m)) => Err(m),
            Err(e) => Err(format!("it cannot be evaluated: {}", problem(&e))),
        }
    }
}

/// Longest expression accepted, in characters.
pub const MAX_LEN: usize = 10_000;
/// Deepest nesting of parentheses, and longest run of signs.
pub(crate) const MAX_DEPTH: usize = 200;
/// Deepest parsed tree (a sum of n terms is n deep; each parenthesis or call adds 1 or 2).
pub(crate) const MAX_TREE_DEPTH: usize = 1000;

/// Refuses, before the parser sees it, a text too long, nested too deep in parentheses, or
/// with a run of signs (`- - - x`) longer than [`MAX_DEPTH`]: the parser's and the
/// evaluator's recursion and time grow with them.
fn check_size(text: &str) -> Result<(), String> {
    let len = text.chars().count();
    if len > MAX_LEN {
        return Err(format!(
            "it is {len} characters long, more than {MAX_LEN}: write a shorter expression"
        ));
    }
    let (mut depth, mut deepest, mut signs, mut most_signs) = (0usize, 0usize, 0usize, 0usize);
    for c in text.chars() {
        match c {
            '(' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            ')' => depth = depth.saturating_sub(1),
            _ => {}
        }
        match c {
            '+' | '-' => {
                signs += 1;
                most_signs = most_signs.max(signs);
            }
            c if c.is_whitespace() || c == '(' => {}
            _ => signs = 0,
        }
    }
    if deepest > MAX_DEPTH {
        return Err(format!(
            "it nests parentheses {deepest} deep, more than {MAX_DEPTH}: simplify it"
        ));
    }
    if most_signs > MAX_DEPTH {
        return Err(format!(
            "it has a run of {most_signs} signs (+ -), more than {MAX_DEPTH}: simplify it"
        ));
    }
    Ok(())
}

/// What is wrong with a text that does not parse or evaluate, in the tool's words.
fn problem(e: &EvalexprError<DefaultNumericTypes>) -> String {
    match e {
        EvalexprError::UnmatchedLBrace | EvalexprError::UnmatchedRBrace => {
            "its parentheses do not match: every `(` needs a `)`".into()
        }
        EvalexprError::MissingOperatorOutsideOfBrace | EvalexprError::AppendedToLeafNode => {
            "two values stand side by side: write the operator between them (2*x, not 2x \
             or 2 x)"
                .into()
        }
        EvalexprError::WrongOperatorArgumentAmount { .. } => {
            "an operator lacks a value on one side (e.g. `x +` or `* y`)".into()
        }
        _ => format!(
            "write arithmetic in x, y, t and pi (+ - * / ^, parentheses) with the functions {}",
            function_list()
        ),
    }
}

/// Depth of a parsed tree, without recursion.
fn tree_depth(tree: &Node<DefaultNumericTypes>) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(tree, 1usize)];
    while let Some((node, d)) = stack.pop() {
        deepest = deepest.max(d);
        for c in node.children() {
            stack.push((c, d + 1));
        }
    }
    deepest
}

fn function_list() -> String {
    FUNCTIONS
        .iter()
        .map(|(f, _)| *f)
        .collect::<Vec<_>>()
        .join(" ")
}

/// Rewrites integer literals as float literals (`2` → `2.0`) so that `/` never truncates.
fn floats_for_integers(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len() + 8);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let starts_number = c.is_ascii_digit()
            && (i == 0
                || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '_' || chars[i - 1] == '.'));
        if !starts_number {
            out.push(c);
            i += 1;
            continue;
        }
        let start = i;
        while i < chars.len() && chars[i].is_ascii_digit() {
            i += 1;
        }
        let mut is_float = false;
        if i < chars.len() && chars[i] == '.' {
            is_float = true;
            i += 1;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
        }
        if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
            let mut j = i + 1;
            if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                j += 1;
            }
            if j < chars.len() && chars[j].is_ascii_digit() {
                is_float = true;
                i = j;
                while i < chars.len() && chars[i].is_ascii_digit() {
                    i += 1;
                }
            }
        }
        out.extend(&chars[start..i]);
        if !is_float {
            out.push_str(".0");
        }
    }
    out
}

/// The evaluation context: x, y, pi and the functions of [`FUNCTIONS`], nothing else.
struct PointContext {
    x: Value,
    y: Value,
    t: Value,
    pi: Value,
}

impl Context for PointContext {
    type NumericTypes = DefaultNumericTypes;

    fn get_value(&self, identifier: &str) -> Option<&Value> {
        match identifier {
            "x" => Some(&self.x),
            "y" => Some(&self.y),
            "t" => Some(&self.t),
            "pi" => Some(&self.pi),
            _ => None,
        }
    }

    fn call_function(&self, identifier: &str, argument: &Value) -> EvalexprResult<Value> {
        // The arguments as numbers; a wrong count or a non-number is named in our words.
        let wanted = FUNCTIONS
            .iter()
            .find(|(f, _)| *f == identifier)
            .map(|(_, n)| *n)
            .ok_or_else(|| EvalexprError::FunctionIdentifierNotFound(identifier.to_string()))?;
        let given: Vec<&Value> = match argument {
            Value::Empty => Vec::new(),
            Value::Tuple(v) => v.iter().collect(),
            v => vec![v],
        };
        let args: Option<Vec<f64>> = given.iter().map(|v| v.as_number().ok()).collect();
        let args = match args {
            Some(a) if a.len() == wanted => a,
            _ => {
                let what = if wanted == 1 {
                    "one number"
                } else {
                    "two numbers"
                };
                return Err(EvalexprError::CustomMessage(format!(
                    "`{identifier}` takes {what}{}, e.g. {identifier}({}); it was given {}",
                    if wanted == 2 {
                        " separated by a comma"
                    } else {
                        ""
                    },
                    if wanted == 1 { "x" } else { "x, y" },
                    match given.len() {
                        0 => "none".to_string(),
                        1 => "one".to_string(),
                        n => n.to_string(),
                    }
                )));
            }
        };
        let v = match identifier {
            "sqrt" => args[0].sqrt(),
            "sin" => args[0].sin(),
            "cos" => args[0].cos(),
            "tan" => args[0].tan(),
            "asin" => args[0].asin(),
            "acos" => args[0].acos(),
            "atan" => args[0].atan(),
            "floor" => args[0].floor(),
            "ceil" => args[0].ceil(),
            "exp" => args[0].exp(),
            "ln" => args[0].ln(),
            "abs" => args[0].abs(),
            "atan2" => args[0].atan2(args[1]),
            "min" => args[0].min(args[1]),
            _ => args[0].max(args[1]),
        };
        Ok(Value::Float(v))
    }

    fn are_builtin_functions_disabled(&self) -> bool {
        true
    }

    fn set_builtin_functions_disabled(&mut self, _disabled: bool) -> EvalexprResult<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(text: &str, p: [f64; 2]) -> f64 {
        Expr::parse(text).expect("parses").eval(p, 1.0)
    }

    /// The worst texts within the limits parse (or are refused) quickly and without
    /// exhausting a 1 MB stack (threads get 2 MB); beyond the limits they are refused before
    /// parsing.
    #[test]
    fn size_and_depth_are_bounded() {
        let run = || {
            let n = MAX_LEN / 2 - 1;
            let m = MAX_TREE_DEPTH - 2;
            let cases: Vec<String> = vec![
                vec!["x"; n].join("+"),
                vec!["x"; n].join("^"),
                vec!["x"; n].join("*-"),
                vec!["x"; m].join("+"),
                vec!["x"; m].join("^"),
                vec!["x"; m / 2].join("*-"),
                format!("{}x{}", "sin(".repeat(m / 8), ")".repeat(m / 8)),
                format!("{}x{}", "(".repeat(MAX_DEPTH), ")".repeat(MAX_DEPTH)),
                format!("{}x{}", "sin(".repeat(MAX_DEPTH), ")".repeat(MAX_DEPTH)),
                format!("{}x", "-".repeat(MAX_DEPTH)),
                format!("{}x", "- ".repeat(MAX_DEPTH)),
                format!("{}x", "-(".repeat(MAX_DEPTH / 2)) + &")".repeat(MAX_DEPTH / 2),
            ];
            let mut out = Vec::new();
            for c in &cases {
                let t = std::time::Instant::now();
                let r = Expr::parse(c).map(|e| e.eval([0.5, 0.5], 1.0));
                out.push((c.len(), r, t.elapsed().as_secs_f64()));
            }
            out
        };
        let results = std::thread::Builder::new()
            .stack_size(1 << 20)
            .spawn(run)
            .expect("thread")
            .join()
            .expect("no stack overflow");
        for (len, r, secs) in &results {
            eprintln!("{len} chars: {r:?} in {secs:.4} s");
            assert!(*secs < 0.5, "{len} chars took {secs} s");
        }
        // Within the limits: evaluated (x = 0.5).
        assert_eq!(results[3].1, Ok(0.5 * (MAX_TREE_DEPTH - 2) as f64));
        assert!(results[6].1.as_ref().is_ok_and(|v| v.is_finite()));
        assert!(results[0]
            .1
            .as_ref()
            .unwrap_err()
            .contains("5000 operations deep"));
        assert!(results[1]
            .1
            .as_ref()
            .unwrap_err()
            .contains("5000 operations deep"));
        assert!(results[2]
            .1
            .as_ref()
            .unwrap_err()
            .contains("characters long"));
        let long = format!("{}+x", "1".repeat(MAX_LEN));
        assert!(Expr::parse(&long).unwrap_err().contains("characters long"));
        let deep = format!(
            "{}x{}",
            "(".repeat(MAX_DEPTH + 1),
            ")".repeat(MAX_DEPTH + 1)
        );
        assert!(Expr::parse(&deep).unwrap_err().contains("parentheses"));
        let signs = format!("{}x", "-".repeat(MAX_DEPTH + 1));
        assert!(Expr::parse(&signs).unwrap_err().contains("signs"));
    }

    #[test]
    fn arithmetic_and_functions() {
        assert_eq!(ev("-9.81e-3*(40 - y)", [0.0, 10.0]), -9.81e-3 * 30.0);
        assert_eq!(ev("x^2/(2*50)", [10.0, 0.0]), 1.0);
        assert_eq!(ev("1/2*x", [3.0, 0.0]), 1.5);
        assert_eq!(ev("7/2", [0.0, 0.0]), 3.5);
        assert_eq!(ev("2E2 + 1.5e+1 + 3.", [0.0, 0.0]), 218.0);
        assert!(
            (ev("sin(pi/2) + cos(0) + tan(0) + exp(0) + ln(1)", [0.0, 0.0]) - 3.0).abs() < 1e-15
        );
        assert_eq!(ev("sqrt(abs(-16))", [0.0, 0.0]), 4.0);
        assert_eq!(ev("atan2(y, x)", [0.0, 1.0]), std::f64::consts::FRAC_PI_2);
        assert_eq!(ev("min(x, y) + max(x, y)", [2.0, 5.0]), 7.0);
        assert_eq!(ev("-(x+y)^2", [1.0, 1.0]), -4.0);
    }

    /// The inverse trigonometric and rounding functions docs/scene.md §9 lists, against closed
    /// values.
    #[test]
    fn inverse_trigonometry_and_rounding() {
        use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, FRAC_PI_6, PI};
        let close = |text: &str, want: f64| {
            let v = ev(text, [0.5, 1.0]);
            assert!(
                (v - want).abs() <= 4.0 * f64::EPSILON,
                "{text} = {v}, want {want}"
            );
        };
        close("atan(1)", FRAC_PI_4);
        close("atan(y)", FRAC_PI_4);
        close("atan(-1)", -FRAC_PI_4);
        close("asin(x)", FRAC_PI_6);
        close("asin(1)", FRAC_PI_2);
        close("acos(x)", PI / 3.0);
        close("acos(-1)", PI);
        close("acos(0)", FRAC_PI_2);
        close("floor(2.7) + ceil(2.2)", 5.0);
        close("floor(-2.5)", -3.0);
        close("ceil(-2.5)", -2.0);
        close("floor(x) + ceil(x)", 1.0);
        close("4*atan(1) - pi", 0.0);
        // Outside its domain a function is not a number (the scene check refuses it).
        assert!(ev("asin(2)", [0.0, 0.0]).is_nan());
    }

    /// Wrong argument counts, tuples and parse errors are told in the tool's words.
    #[test]
    fn messages_name_the_function_and_never_the_evaluator() {
        let cases = [
            ("min()", "`min` takes two numbers"),
            ("min(x)", "it was given one"),
            ("max(x, y, t)", "it was given 3"),
            ("sin()", "`sin` takes one number"),
            ("sqrt(x, y)", "it was given 2"),
            ("atan(1, 2)", "`atan` takes one number"),
            ("x, y", "2 values separated by commas"),
            ("(x + 1", "parentheses do not match"),
            ("x + 1)", "parentheses do not match"),
            ("2 x", "side by side"),
            ("x +", "lacks a value"),
            ("()", "no value"),
        ];
        for (text, want) in cases {
            let e = Expr::parse(text).unwrap_err();
            assert!(e.contains(want), "{text}: {e}");
            for internal in ["Value::", "Tuple", "Empty", "Expected", "Node", "token"] {
                assert!(!e.contains(internal), "{text}: {e}");
            }
        }
    }

    #[test]
    fn pseudo_time_is_a_variable() {
        let e = Expr::parse("5*max(t - 1, 0) + x").expect("parses");
        assert_eq!(e.eval([2.0, 0.0], 0.5), 2.0);
        assert_eq!(e.eval([2.0, 0.0], 3.0), 12.0);
        let s = Scalar::Expr(e);
        assert!(s.uses_time() && s.uses_space());
        let s = Scalar::Expr(Expr::parse("2*t").expect("parses"));
        assert!(s.uses_time() && !s.uses_space());
        assert!(!Scalar::Const(1.0).uses_time());
    }

    #[test]
    fn identifiers_with_digits_are_untouched() {
        assert_eq!(floats_for_integers("x2 + 3*y_1"), "x2 + 3.0*y_1");
        assert_eq!(floats_for_integers("1.5e-3 + 10"), "1.5e-3 + 10.0");
    }

    #[test]
    fn bad_expressions_are_refused_with_a_reason() {
        let e = Expr::parse("z + 1").unwrap_err();
        assert!(e.contains("`z`"), "{e}");
        let e = Expr::parse("sinh(x)").unwrap_err();
        assert!(
            e.contains("`sinh`") && e.contains("did you mean `sin`"),
            "{e}"
        );
        let e = Expr::parse("x = 3").unwrap_err();
        assert!(e.contains("`=`"), "{e}");
        assert!(Expr::parse("(x + 1").is_err());
        assert!(Expr::parse("").is_err());
        assert!(Expr::parse("atan2(x)").is_err());
        assert!(Expr::parse("\"text\"").is_err());
        assert!(Expr::parse("math::sin(x)").is_err());
    }
}
