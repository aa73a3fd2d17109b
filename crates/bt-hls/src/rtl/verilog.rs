//! A small Verilog-2005 AST and its one printer.
//!
//! Every generated file goes through [`Module`] and [`print_module`]; the printer is the only
//! place that knows Verilog syntax. All vectors are unsigned: two's-complement arithmetic is
//! spelled out by the generator (explicit sign extension, slices for arithmetic shifts), so no
//! expression depends on Verilog's signedness rules, with one exception kept in one place:
//! [`Signal::signed_product`], a signed product assigned alone to a wire of exactly its width
//! (so that the context can neither widen nor unsign it). Output is a pure function of the AST.

use std::fmt::Write as _;

/// An expression.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Expr {
    /// A net, register or localparam name.
    Ident(String),
    /// A sized literal `width'hvalue` (value masked to `width` bits, two's complement).
    Lit {
        /// Width in bits (≥ 1).
        width: u32,
        /// Value (low `width` bits are printed).
        value: u128,
    },
    /// Bit select with a dynamic or constant index: `base[index]`.
    Index(Box<Expr>, Box<Expr>),
    /// Part select `base[hi:lo]` on a name.
    Slice(String, u32, u32),
    /// Concatenation `{a, b, ...}` (most significant first).
    Concat(Vec<Expr>),
    /// Replication `{n{e}}` (n ≥ 1).
    Repeat(u32, Box<Expr>),
    /// Unary operator.
    Unary(UnaryOp, Box<Expr>),
    /// Binary operator (always printed parenthesised).
    Binary(BinaryOp, Box<Expr>, Box<Expr>),
    /// `c ? a : b`.
    Ternary(Box<Expr>, Box<Expr>, Box<Expr>),
    /// `($signed(a) * $signed(b))`: only built by [`Signal::signed_product`], as the whole
    /// right-hand side of a wire as wide as both operands together.
    SignedProduct(Box<Expr>, Box<Expr>),
}

/// Unary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnaryOp {
    /// `~`
    Not,
    /// `!`
    LogicNot,
    /// `&` (reduction)
    ReduceAnd,
    /// `|` (reduction)
    ReduceOr,
}

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinaryOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `&`
    And,
    /// `|`
    Or,
    /// `^`
    Xor,
    /// `&&`
    LogicAnd,
    /// `||`
    LogicOr,
    /// `==`
    Eq,
    /// `!=`
    Ne,
    /// `<` (unsigned)
    Lt,
    /// `>` (unsigned)
    Gt,
}

impl Expr {
    /// A name.
    pub fn id(name: impl Into<String>) -> Expr {
        Expr::Ident(name.into())
    }
    /// A sized literal; `value` is masked to `width` bits.
    pub fn lit(width: u32, value: u128) -> Expr {
        Expr::Lit { width, value }
    }
    /// A sized literal from a signed value (two's complement in `width` bits).
    pub fn lit_signed(width: u32, value: i128) -> Expr {
        Expr::Lit {
            width,
            value: value as u128,
        }
    }
    /// `name[hi:lo]`.
    pub fn slice(name: impl Into<String>, hi: u32, lo: u32) -> Expr {
        Expr::Slice(name.into(), hi, lo)
    }
    /// `name[bit]` with a constant bit.
    pub fn bit(name: impl Into<String>, bit: u32) -> Expr {
        Expr::Slice(name.into(), bit, bit)
    }
    /// `self[index]` with a dynamic index.
    pub fn at(self, index: Expr) -> Expr {
        Expr::Index(Box::new(self), Box::new(index))
    }
    /// `{parts...}`.
    pub fn concat(parts: Vec<Expr>) -> Expr {
        Expr::Concat(parts)
    }
    /// `{n{self}}`.
    pub fn repeat(self, n: u32) -> Expr {
        Expr::Repeat(n, Box::new(self))
    }
    /// `c ? a : b`.
    pub fn mux(c: Expr, a: Expr, b: Expr) -> Expr {
        Expr::Ternary(Box::new(c), Box::new(a), Box::new(b))
    }
    /// Binary operation.
    pub fn bin(op: BinaryOp, a: Expr, b: Expr) -> Expr {
        Expr::Binary(op, Box::new(a), Box::new(b))
    }
    /// `self + b`.
    pub fn plus(self, b: Expr) -> Expr {
        Expr::bin(BinaryOp::Add, self, b)
    }
    /// `self - b`.
    pub fn minus(self, b: Expr) -> Expr {
        Expr::bin(BinaryOp::Sub, self, b)
    }
    /// `self == b`.
    pub fn eq(self, b: Expr) -> Expr {
        Expr::bin(BinaryOp::Eq, self, b)
    }
    /// `self && b`.
    pub fn and(self, b: Expr) -> Expr {
        Expr::bin(BinaryOp::LogicAnd, self, b)
    }
    /// `self || b`.
    pub fn or(self, b: Expr) -> Expr {
        Expr::bin(BinaryOp::LogicOr, self, b)
    }
    /// `~self`.
    pub fn inv(self) -> Expr {
        Expr::Unary(UnaryOp::Not, Box::new(self))
    }
    /// `!self`.
    pub fn lnot(self) -> Expr {
        Expr::Unary(UnaryOp::LogicNot, Box::new(self))
    }
}

/// A declared net or register: the one spelling of its name. A builder declares a signal once
/// and hands the handle to the blocks that read it, so a misspelt name is a compile error
/// rather than a silent new wire.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Signal {
    name: String,
    width: u32,
}

impl Signal {
    /// Declares `wire [width-1:0] name;` in `items`.
    pub fn wire(items: &mut Vec<Item>, name: impl Into<String>, width: u32) -> Signal {
        let s = Signal {
            name: name.into(),
            width,
        };
        items.push(Item::Wire(s.name.clone(), width));
        s
    }
    /// Declares a wire and its `assign name = value;` in `items`.
    pub fn assigned(
        items: &mut Vec<Item>,
        name: impl Into<String>,
        width: u32,
        value: Expr,
    ) -> Signal {
        let s = Signal::wire(items, name, width);
        items.push(Item::Assign(s.e(), value));
        s
    }
    /// Declares the `(a_width + b_width)`-bit wire `name = $signed(a) * $signed(b)`: the
    /// exact two's-complement product of `a` (`a_width` bits) and `b` (`b_width` bits). The
    /// wire is exactly as wide as the product, so Verilog's rules sign-extend both operands to
    /// it and nothing around the expression can change that; Yosys sees one signed `$mul`.
    pub fn signed_product(
        items: &mut Vec<Item>,
        name: impl Into<String>,
        (a, a_width): (Expr, u32),
        (b, b_width): (Expr, u32),
    ) -> Signal {
        let value = Expr::SignedProduct(Box::new(a), Box::new(b));
        Signal::assigned(items, name, a_width + b_width, value)
    }
    /// A handle on a port of the module being built (declared by its port list, not in
    /// `items`).
    pub fn port(name: impl Into<String>, width: u32) -> Signal {
        Signal {
            name: name.into(),
            width,
        }
    }
    /// Declares `reg [width-1:0] name;` in `items`.
    pub fn reg(items: &mut Vec<Item>, name: impl Into<String>, width: u32) -> Signal {
        let s = Signal {
            name: name.into(),
            width,
        };
        items.push(Item::Reg(s.name.clone(), width));
        s
    }
    /// Declares `reg [width-1:0] name [0:depth-1];` in `items`: a memory of `depth` words of
    /// `width` bits, read and written word by word ([`Signal::at`]).
    pub fn memory(
        items: &mut Vec<Item>,
        name: impl Into<String>,
        width: u32,
        depth: u32,
    ) -> Signal {
        let s = Signal {
            name: name.into(),
            width,
        };
        items.push(Item::Memory(s.name.clone(), width, depth));
        s
    }
    /// The name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Width in bits.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// The signal as an expression.
    pub fn e(&self) -> Expr {
        Expr::id(self.name.clone())
    }
    /// `name[hi:lo]`.
    pub fn slice(&self, hi: u32, lo: u32) -> Expr {
        Expr::slice(self.name.clone(), hi, lo)
    }
    /// `name[bit]`.
    pub fn bit(&self, bit: u32) -> Expr {
        Expr::bit(self.name.clone(), bit)
    }
    /// `name[index]` with a dynamic index: a bit of a vector, or a word of a memory.
    pub fn at(&self, index: Expr) -> Expr {
        self.e().at(index)
    }
}

/// A statement inside an `always` block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Stmt {
    /// `lhs <= rhs;` (sequential blocks).
    NonBlocking(Expr, Expr),
    /// `lhs = rhs;` (combinational blocks).
    Blocking(Expr, Expr),
    /// `if (c) ... else ...`.
    If(Expr, Vec<Stmt>, Vec<Stmt>),
    /// `case (subject) label: ...; default: ...; endcase`.
    Case(Expr, Vec<(Expr, Vec<Stmt>)>, Vec<Stmt>),
}

/// Port direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// `input wire`
    Input,
    /// `output wire`
    Output,
    /// `output reg`
    OutputReg,
}

/// A port of a module.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Port {
    /// Name.
    pub name: String,
    /// Direction.
    pub dir: Direction,
    /// Width in bits.
    pub width: u32,
}

/// A module item.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Item {
    /// `// text` (one line per `\n`).
    Comment(String),
    /// `localparam [w-1:0] NAME = w'hvalue;`
    LocalParam(String, u32, u128),
    /// `wire [w-1:0] name;`
    Wire(String, u32),
    /// `reg [w-1:0] name;`
    Reg(String, u32),
    /// `reg [w-1:0] name [0:depth-1];`
    Memory(String, u32, u32),
    /// `assign lhs = rhs;`
    Assign(Expr, Expr),
    /// `always @(posedge clk) begin ... end`
    AlwaysFf(Vec<Stmt>),
    /// `always @* begin ... end`
    AlwaysComb(Vec<Stmt>),
    /// `module_name instance_name (.port(expr), ...);`
    Instance {
        /// Module name.
        module: String,
        /// Instance name.
        name: String,
        /// Port connections in order.
        ports: Vec<(String, Expr)>,
    },
}

/// A module.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Module {
    /// Module name (also the file name, `<name>.v`).
    pub name: String,
    /// Leading comment lines.
    pub header: Vec<String>,
    /// Ports in order.
    pub ports: Vec<Port>,
    /// Body.
    pub items: Vec<Item>,
}

fn range(width: u32) -> String {
    if width == 1 {
        String::new()
    } else {
        format!("[{}:0] ", width - 1)
    }
}

fn literal(width: u32, value: u128) -> String {
    let masked = if width >= 128 {
        value
    } else {
        value & ((1u128 << width) - 1)
    };
    if width <= 8 {
        format!("{width}'d{masked}")
    } else {
        format!("{width}'h{masked:x}")
    }
}

/// Prints an expression.
pub fn print_expr(e: &Expr) -> String {
    match e {
        Expr::Ident(n) => n.clone(),
        Expr::Lit { width, value } => literal(*width, *value),
        Expr::Index(b, i) => format!("{}[{}]", print_expr(b), print_expr(i)),
        Expr::Slice(n, hi, lo) if hi == lo => format!("{n}[{hi}]"),
        Expr::Slice(n, hi, lo) => format!("{n}[{hi}:{lo}]"),
        Expr::Concat(parts) => {
            let inner: Vec<String> = parts.iter().map(print_expr).collect();
            format!("{{{}}}", inner.join(", "))
        }
        Expr::Repeat(n, e) => format!("{{{n}{{{}}}}}", print_expr(e)),
        Expr::Unary(op, e) => {
            let o = match op {
                UnaryOp::Not => "~",
                UnaryOp::LogicNot => "!",
                UnaryOp::ReduceAnd => "&",
                UnaryOp::ReduceOr => "|",
            };
            format!("{o}({})", print_expr(e))
        }
        Expr::Binary(op, a, b) => {
            let o = match op {
                BinaryOp::Add => "+",
                BinaryOp::Sub => "-",
                BinaryOp::And => "&",
                BinaryOp::Or => "|",
                BinaryOp::Xor => "^",
                BinaryOp::LogicAnd => "&&",
                BinaryOp::LogicOr => "||",
                BinaryOp::Eq => "==",
                BinaryOp::Ne => "!=",
                BinaryOp::Lt => "<",
                BinaryOp::Gt => ">",
            };
            format!("({} {o} {})", print_expr(a), print_expr(b))
        }
        Expr::SignedProduct(a, b) => {
            format!("($signed({}) * $signed({}))", print_expr(a), print_expr(b))
        }
        Expr::Ternary(c, a, b) => format!(
            "({} ? {} : {})",
            print_expr(c),
            print_expr(a),
            print_expr(b)
        ),
    }
}

fn print_stmts(out: &mut String, stmts: &[Stmt], indent: usize) {
    for s in stmts {
        print_stmt(out, s, indent);
    }
}

fn print_stmt(out: &mut String, s: &Stmt, indent: usize) {
    let pad = "  ".repeat(indent);
    match s {
        Stmt::NonBlocking(l, r) => {
            let _ = writeln!(out, "{pad}{} <= {};", print_expr(l), print_expr(r));
        }
        Stmt::Blocking(l, r) => {
            let _ = writeln!(out, "{pad}{} = {};", print_expr(l), print_expr(r));
        }
        Stmt::If(c, t, e) => {
            let _ = writeln!(out, "{pad}if ({}) begin", print_expr(c));
            print_stmts(out, t, indent + 1);
            if e.is_empty() {
                let _ = writeln!(out, "{pad}end");
            } else {
                let _ = writeln!(out, "{pad}end else begin");
                print_stmts(out, e, indent + 1);
                let _ = writeln!(out, "{pad}end");
            }
        }
        Stmt::Case(subject, arms, default) => {
            let _ = writeln!(out, "{pad}case ({})", print_expr(subject));
            for (label, body) in arms {
                let _ = writeln!(out, "{pad}  {}: begin", print_expr(label));
                print_stmts(out, body, indent + 2);
                let _ = writeln!(out, "{pad}  end");
            }
            let _ = writeln!(out, "{pad}  default: begin");
            print_stmts(out, default, indent + 2);
            let _ = writeln!(out, "{pad}  end");
            let _ = writeln!(out, "{pad}endcase");
        }
    }
}

/// One comment line as it is printed: every control character (a line break, a carriage
/// return, an escape sequence, a NUL), which could end the comment or reach a terminal, is
/// written as a Rust-style escape (`\n`, `\u{1b}`). Names from the input reach the RTL only
/// through here.
fn comment_line(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c.is_control() || matches!(c, '\u{2028}' | '\u{2029}' | '\u{85}') {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// Prints a module as a complete Verilog-2005 file.
pub fn print_module(m: &Module) -> String {
    let mut out = String::new();
    for line in &m.header {
        let _ = writeln!(out, "// {}", comment_line(line));
    }
    let _ = writeln!(out, "`timescale 1ns / 1ps");
    let _ = writeln!(out, "`default_nettype none");
    let _ = writeln!(out, "module {} (", m.name);
    for (i, p) in m.ports.iter().enumerate() {
        let dir = match p.dir {
            Direction::Input => "input  wire",
            Direction::Output => "output wire",
            Direction::OutputReg => "output reg ",
        };
        let comma = if i + 1 == m.ports.len() { "" } else { "," };
        let _ = writeln!(out, "  {dir} {}{}{comma}", range(p.width), p.name);
    }
    let _ = writeln!(out, ");");
    for item in &m.items {
        match item {
            Item::Comment(text) => {
                for line in text.split('\n') {
                    let _ = writeln!(out, "  // {}", comment_line(line));
                }
            }
            Item::LocalParam(n, w, v) => {
                let _ = writeln!(out, "  localparam {}{n} = {};", range(*w), literal(*w, *v));
            }
            Item::Wire(n, w) => {
                let _ = writeln!(out, "  wire {}{n};", range(*w));
            }
            Item::Reg(n, w) => {
                let _ = writeln!(out, "  reg {}{n};", range(*w));
            }
            Item::Memory(n, w, depth) => {
                let _ = writeln!(out, "  reg {}{n} [0:{}];", range(*w), depth - 1);
            }
            Item::Assign(l, r) => {
                let _ = writeln!(out, "  assign {} = {};", print_expr(l), print_expr(r));
            }
            Item::AlwaysFf(body) => {
                let _ = writeln!(out, "  always @(posedge clk) begin");
                print_stmts(&mut out, body, 2);
                let _ = writeln!(out, "  end");
            }
            Item::AlwaysComb(body) => {
                let _ = writeln!(out, "  always @* begin");
                print_stmts(&mut out, body, 2);
                let _ = writeln!(out, "  end");
            }
            Item::Instance {
                module,
                name,
                ports,
            } => {
                let _ = writeln!(out, "  {module} {name} (");
                for (i, (p, e)) in ports.iter().enumerate() {
                    let comma = if i + 1 == ports.len() { "" } else { "," };
                    let _ = writeln!(out, "    .{p}({}){comma}", print_expr(e));
                }
                let _ = writeln!(out, "  );");
            }
        }
    }
    let _ = writeln!(out, "endmodule");
    let _ = writeln!(out, "`default_nettype wire");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prints_a_tiny_module() {
        let m = Module {
            name: "bt_demo".into(),
            header: vec!["demo".into()],
            ports: vec![
                Port {
                    name: "clk".into(),
                    dir: Direction::Input,
                    width: 1,
                },
                Port {
                    name: "a".into(),
                    dir: Direction::Input,
                    width: 8,
                },
                Port {
                    name: "q".into(),
                    dir: Direction::OutputReg,
                    width: 8,
                },
            ],
            items: vec![Item::AlwaysFf(vec![Stmt::NonBlocking(
                Expr::id("q"),
                Expr::id("a").plus(Expr::lit(8, 0x1ff)),
            )])],
        };
        let text = print_module(&m);
        assert!(text.contains("output reg  [7:0] q"), "{text}");
        assert!(text.contains("q <= (a + 8'd255);"), "{text}");
        assert_eq!(text, print_module(&m));
    }

    /// The injection of issue 9: a name that closes the comment line and opens a module.
    const INJECTION: &str =
        "wall\nmodule pwn; initial $display(\"pwned\"); endmodule\n//\r\u{1b}[31m\0";

    #[test]
    fn names_in_comments_never_become_code() {
        let m = Module {
            name: "bt_demo".into(),
            header: vec![format!("plane 0 ('{INJECTION}')")],
            ports: vec![],
            items: vec![Item::Comment(format!("plane 0 '{INJECTION}'"))],
        };
        let text = print_module(&m);
        let code: Vec<&str> = text
            .lines()
            .map(str::trim_start)
            .filter(|l| !l.starts_with("//"))
            .collect();
        assert!(code.iter().all(|l| !l.contains("pwn")), "{text}");
        assert_eq!(
            code.iter().filter(|l| l.starts_with("module ")).count(),
            1,
            "{text}"
        );
        assert!(
            !text.chars().any(|c| c.is_control() && c != '\n'),
            "{text:?}"
        );
        assert!(text.contains("\\u{1b}[31m"), "{text}");
    }
}
