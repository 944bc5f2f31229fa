//! A restricted reader of Python pickles, for the body-model files of the SMPL family
//! (SMPL, SMPL-H, MANO, FLAME `.pkl`: mostly Python 2 chumpy pickles, protocol 2).
//!
//! **It never runs pickled code.** Python's own unpickler *calls* whatever global a file
//! names; this one interprets the opcodes itself and accepts only the globals in
//! [`ALLOWED`], each given a meaning here:
//!
//! | global | what it builds |
//! |---|---|
//! | `numpy.core.multiarray._reconstruct` (also `numpy._core.…`), `numpy.ndarray` | an ndarray; its `BUILD` state `(version, shape, dtype, fortran, data)` gives the values |
//! | `numpy.dtype` | a dtype; its `BUILD` state gives the byte order |
//! | `numpy.core.multiarray.scalar` (also `numpy._core.…`) | a 0-d array |
//! | `chumpy.ch.Ch`, `chumpy.reordering.*`, `chumpy.ch_ops.*` | an [`PyValue::Object`] with its state dict (a `Ch` keeps its array under `x`) |
//! | `scipy.sparse.csc.csc_matrix`, `scipy.sparse._csc.csc_matrix` | an [`PyValue::Object`] with its state dict (`data`, `indices`, `indptr`, `_shape`) |
//! | `copy_reg._reconstructor`, `copyreg._reconstructor`, `__builtin__.object`, `builtins.object` | how Python 2 pickles those objects: `_reconstructor(cls, object, None)` is `cls` made empty |
//! | `_codecs.encode` | how Python 3 writes `bytes` at protocol 2: `encode(text, 'latin1')` |
//!
//! Any other global is refused, naming it. Protocols 0 to 5 are read, except persistent
//! ids, extension codes and out-of-band buffers. Python 2 byte strings (`str`) are read as
//! the unpickler's `encoding='latin1'` does: as text when they are text, as bytes when an
//! array's data.
//!
//! **Bounds.** Every length is checked against the bytes left before anything is
//! allocated, so parsing allocates O(input). Objects live in an arena and are shared by
//! id, as Python shares them (a `BUILD` after a memo `PUT` must reach the memoised object);
//! turning the arena into [`PyValue`]s (which copies shared objects) is bounded by a budget
//! of [`BUDGET_FACTOR`] × the input's size, and by a nesting depth of [`MAX_DEPTH`], so a
//! cycle or a doubling chain of shared lists is refused instead of exhausting memory.

use std::collections::HashMap;

use crate::npz::{AnyArray, decode_array_data};

/// A value read from a pickle: Python's plain types, numpy arrays, and the allowed classes'
/// objects with their state.
#[derive(Debug, Clone, PartialEq)]
pub enum PyValue {
    None,
    Bool(bool),
    Int(i64),
    /// An integer past i64: its two's-complement little-endian bytes, as pickled.
    BigInt(Vec<u8>),
    Float(f64),
    Str(String),
    Bytes(Vec<u8>),
    List(Vec<PyValue>),
    Tuple(Vec<PyValue>),
    /// Entries in insertion order (a later equal key replaces an earlier one).
    Dict(Vec<(PyValue, PyValue)>),
    Set(Vec<PyValue>),
    Array(AnyArray),
    /// A value this reader cannot represent (an ndarray of Python objects), with why:
    /// kept in place so the rest of the file still reads.
    Unreadable(String),
    /// An instance of an allowed class (`chumpy.ch.Ch`, a scipy CSC matrix, …): the
    /// class as `module.name`, the constructor's arguments, the `BUILD` state.
    Object {
        class: String,
        args: Vec<PyValue>,
        state: Option<Box<PyValue>>,
    },
}

impl PyValue {
    /// The value of `key` in a dict with string keys.
    pub fn get(&self, key: &str) -> Option<&PyValue> {
        match self {
            PyValue::Dict(entries) => {
                entries.iter().rev().find(|(k, _)| matches!(k, PyValue::Str(s) if s == key)).map(|(_, v)| v)
            }
            _ => None,
        }
    }

    /// A short name of the value's type, for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            PyValue::None => "None",
            PyValue::Bool(_) => "bool",
            PyValue::Int(_) | PyValue::BigInt(_) => "int",
            PyValue::Float(_) => "float",
            PyValue::Str(_) => "str",
            PyValue::Bytes(_) => "bytes",
            PyValue::List(_) => "list",
            PyValue::Tuple(_) => "tuple",
            PyValue::Dict(_) => "dict",
            PyValue::Set(_) => "set",
            PyValue::Array(_) => "ndarray",
            PyValue::Unreadable(_) => "unreadable",
            PyValue::Object { .. } => "object",
        }
    }
}

/// The globals a pickle may name: exact `(module, name)` pairs, or `(module, "*")` for
/// every name in a module.
pub const ALLOWED: &[(&str, &str)] = &[
    ("numpy.core.multiarray", "_reconstruct"),
    ("numpy._core.multiarray", "_reconstruct"),
    ("numpy.core.multiarray", "scalar"),
    ("numpy._core.multiarray", "scalar"),
    ("numpy", "ndarray"),
    ("numpy", "dtype"),
    ("chumpy.ch", "Ch"),
    ("chumpy.reordering", "*"),
    ("chumpy.ch_ops", "*"),
    ("scipy.sparse.csc", "csc_matrix"),
    ("scipy.sparse._csc", "csc_matrix"),
    ("copy_reg", "_reconstructor"),
    ("copyreg", "_reconstructor"),
    ("__builtin__", "object"),
    ("builtins", "object"),
    ("_codecs", "encode"),
];

/// Nesting deeper than this (or a cycle) is refused.
pub const MAX_DEPTH: usize = 100;
/// The conversion to [`PyValue`]s may produce at most this many units (one per value,
/// plus its bytes) per input byte, plus 1 MiB.
pub const BUDGET_FACTOR: usize = 8;
const BUDGET_SLACK: usize = 1 << 20;

/// Reads the pickle in `bytes` (one object, up to its `STOP`; trailing bytes ignored, as
/// Python does). Errors name the opcode and its byte offset.
pub fn unpickle(bytes: &[u8]) -> Result<PyValue, String> {
    let budget = bytes.len().saturating_mul(BUDGET_FACTOR).saturating_add(BUDGET_SLACK);
    let mut machine =
        Machine { input: bytes, at: 0, nodes: Vec::new(), stack: Vec::new(), marks: Vec::new(), budget };
    let root = machine.run()?;
    let mut budget = machine.budget;
    machine.value(root, 0, &mut budget)
}

// ---- the arena ----

type Id = usize;

/// What a global the file names stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Callable {
    Reconstruct,
    Scalar,
    NdarrayClass,
    Dtype,
    Reconstructor,
    ObjectClass,
    Encode,
    /// An allowed class whose instances become [`PyValue::Object`] (index into `classes`).
    Class,
}

#[derive(Debug, Clone)]
enum Node {
    None,
    Bool(bool),
    Int(i64),
    BigInt(Vec<u8>),
    Float(f64),
    Str(String),
    /// A Python 2 `str`: text to a latin1 unpickler, bytes to an ndarray's state.
    Str8(Vec<u8>),
    Bytes(Vec<u8>),
    List(Vec<Id>),
    Tuple(Vec<Id>),
    Dict(Vec<(Id, Id)>),
    Set(Vec<Id>),
    Global {
        callable: Callable,
        qualified: String,
    },
    Dtype {
        name: String,
        state: Option<Id>,
    },
    Array {
        state: Option<Id>,
    },
    Scalar {
        dtype: Id,
        data: Id,
    },
    Object {
        class: String,
        args: Vec<Id>,
        state: Option<Id>,
    },
}

struct Machine<'a> {
    input: &'a [u8],
    at: usize,
    nodes: Vec<Node>,
    stack: Vec<Id>,
    /// Stack lengths at each MARK.
    marks: Vec<usize>,
    /// Work left: copying a call's arguments (a memoised tuple may be called with many
    /// times) is charged here, so parsing stays linear in the input too.
    budget: usize,
}

impl Machine<'_> {
    fn run(&mut self) -> Result<Id, String> {
        let mut memo: HashMap<u64, Id> = HashMap::new();
        loop {
            let offset = self.at;
            let op = self.take(1)?[0];
            let fail = |e: String| format!("opcode 0x{op:02x} at byte {offset}: {e}");
            match op {
                b'.' => return self.pop().map_err(fail),
                0x80 => {
                    let proto = self.take(1)?[0];
                    if proto > 5 {
                        return Err(fail(format!("pickle protocol {proto} is newer than 5")));
                    }
                }
                0x95 => {
                    self.take(8)?; // FRAME: a length hint only
                }
                b'(' => self.marks.push(self.stack.len()),
                b'0' => {
                    self.pop().map_err(fail)?;
                }
                b'1' => {
                    self.pop_mark().map_err(fail)?;
                }
                b'2' => {
                    let top = *self.stack.last().ok_or_else(|| fail("DUP on an empty stack".into()))?;
                    self.stack.push(top);
                }
                b'N' => self.push(Node::None),
                0x88 => self.push(Node::Bool(true)),
                0x89 => self.push(Node::Bool(false)),
                b'J' => {
                    let v = i32::from_le_bytes(self.take(4)?.try_into().unwrap());
                    self.push(Node::Int(v.into()));
                }
                b'K' => {
                    let v = self.take(1)?[0];
                    self.push(Node::Int(v.into()));
                }
                b'M' => {
                    let v = u16::from_le_bytes(self.take(2)?.try_into().unwrap());
                    self.push(Node::Int(v.into()));
                }
                0x8a => {
                    let n = self.take(1)?[0] as usize;
                    let bytes = self.take(n)?.to_vec();
                    self.push(long_node(bytes));
                }
                0x8b => {
                    let n = self.take_len4()?;
                    let bytes = self.take(n)?.to_vec();
                    self.push(long_node(bytes));
                }
                b'I' | b'L' => {
                    let line = self.line()?;
                    let text = line.trim_end_matches('L');
                    let node = match text {
                        "01" if op == b'I' => Node::Bool(true),
                        "00" if op == b'I' => Node::Bool(false),
                        _ => Node::Int(text.parse().map_err(|_| fail(format!("bad integer '{line}'")))?),
                    };
                    self.push(node);
                }
                b'G' => {
                    let v = f64::from_be_bytes(self.take(8)?.try_into().unwrap());
                    self.push(Node::Float(v));
                }
                b'F' => {
                    let line = self.line()?;
                    self.push(Node::Float(line.parse().map_err(|_| fail(format!("bad float '{line}'")))?));
                }
                b'U' => {
                    let n = self.take(1)?[0] as usize;
                    let bytes = self.take(n)?.to_vec();
                    self.push(Node::Str8(bytes));
                }
                b'T' => {
                    let n = self.take_len4()?;
                    let bytes = self.take(n)?.to_vec();
                    self.push(Node::Str8(bytes));
                }
                b'S' => {
                    let line = self.line()?;
                    let bytes = unquote(&line).ok_or_else(|| fail(format!("bad string literal {line}")))?;
                    self.push(Node::Str8(bytes));
                }
                b'C' => {
                    let n = self.take(1)?[0] as usize;
                    let bytes = self.take(n)?.to_vec();
                    self.push(Node::Bytes(bytes));
                }
                b'B' => {
                    let n = self.take_len4()?;
                    let bytes = self.take(n)?.to_vec();
                    self.push(Node::Bytes(bytes));
                }
                0x8e | 0x96 => {
                    let n = self.take_len8()?;
                    let bytes = self.take(n)?.to_vec();
                    self.push(Node::Bytes(bytes));
                }
                0x8c => {
                    let n = self.take(1)?[0] as usize;
                    let text = self.text(n).map_err(fail)?;
                    self.push(Node::Str(text));
                }
                b'X' => {
                    let n = self.take_len4()?;
                    let text = self.text(n).map_err(fail)?;
                    self.push(Node::Str(text));
                }
                0x8d => {
                    let n = self.take_len8()?;
                    let text = self.text(n).map_err(fail)?;
                    self.push(Node::Str(text));
                }
                b'V' => {
                    let line = self.line()?;
                    let text =
                        raw_unicode_unescape(&line).ok_or_else(|| fail("bad unicode literal".into()))?;
                    self.push(Node::Str(text));
                }
                b')' => self.push(Node::Tuple(Vec::new())),
                b']' => self.push(Node::List(Vec::new())),
                b'}' => self.push(Node::Dict(Vec::new())),
                0x8f => self.push(Node::Set(Vec::new())),
                b't' => {
                    let items = self.pop_mark().map_err(fail)?;
                    self.push(Node::Tuple(items));
                }
                0x85..=0x87 => {
                    let n = (op - 0x84) as usize;
                    let at = self.stack.len().checked_sub(n).ok_or_else(|| fail("stack underflow".into()))?;
                    if self.marks.last().is_some_and(|&m| m > at) {
                        return Err(fail("a tuple across a MARK".into()));
                    }
                    let items = self.stack.split_off(at);
                    self.push(Node::Tuple(items));
                }
                b'l' => {
                    let items = self.pop_mark().map_err(fail)?;
                    self.push(Node::List(items));
                }
                0x91 => {
                    let items = self.pop_mark().map_err(fail)?;
                    self.push(Node::Set(items));
                }
                b'd' => {
                    let items = self.pop_mark().map_err(fail)?;
                    let pairs = pairs(items).map_err(fail)?;
                    self.push(Node::Dict(pairs));
                }
                b'a' => {
                    let item = self.pop().map_err(fail)?;
                    self.extend_list(vec![item]).map_err(fail)?;
                }
                b'e' => {
                    let items = self.pop_mark().map_err(fail)?;
                    self.extend_list(items).map_err(fail)?;
                }
                0x90 => {
                    let items = self.pop_mark().map_err(fail)?;
                    let target = self.top().map_err(fail)?;
                    match &mut self.nodes[target] {
                        Node::Set(v) => v.extend(items),
                        _ => return Err(fail("ADDITEMS on a non-set".into())),
                    }
                }
                b's' => {
                    let value = self.pop().map_err(fail)?;
                    let key = self.pop().map_err(fail)?;
                    self.set_items(vec![(key, value)]).map_err(fail)?;
                }
                b'u' => {
                    let items = self.pop_mark().map_err(fail)?;
                    let items = pairs(items).map_err(fail)?;
                    self.set_items(items).map_err(fail)?;
                }
                b'c' => {
                    let module = self.line()?;
                    let name = self.line()?;
                    let node = global(&module, &name).map_err(fail)?;
                    self.push(node);
                }
                0x93 => {
                    let name = self.pop().map_err(fail)?;
                    let module = self.pop().map_err(fail)?;
                    let (Node::Str(module), Node::Str(name)) = (&self.nodes[module], &self.nodes[name])
                    else {
                        return Err(fail("STACK_GLOBAL needs two strings".into()));
                    };
                    let node = global(module, name).map_err(fail)?;
                    self.push(node);
                }
                b'i' => {
                    let module = self.line()?;
                    let name = self.line()?;
                    self.nodes.push(global(&module, &name).map_err(fail)?);
                    let class = self.nodes.len() - 1;
                    let args = self.pop_mark().map_err(fail)?;
                    let node = self.call(class, args).map_err(fail)?;
                    self.push(node);
                }
                b'o' => {
                    let mut items = self.pop_mark().map_err(fail)?;
                    if items.is_empty() {
                        return Err(fail("OBJ without a class".into()));
                    }
                    let class = items.remove(0);
                    let node = self.call(class, items).map_err(fail)?;
                    self.push(node);
                }
                b'R' => {
                    let args = self.pop().map_err(fail)?;
                    let callable = self.pop().map_err(fail)?;
                    let args = self.arguments(args).map_err(fail)?;
                    let node = self.call(callable, args).map_err(fail)?;
                    self.push(node);
                }
                0x81 | 0x92 => {
                    if op == 0x92 {
                        self.pop().map_err(fail)?; // NEWOBJ_EX's keyword arguments
                    }
                    let args = self.pop().map_err(fail)?;
                    let class = self.pop().map_err(fail)?;
                    let args = self.arguments(args).map_err(fail)?;
                    let node = self.new_object(class, args).map_err(fail)?;
                    self.push(node);
                }
                b'b' => {
                    let state = self.pop().map_err(fail)?;
                    let target = self.top().map_err(fail)?;
                    match &mut self.nodes[target] {
                        Node::Dtype { state: s, .. }
                        | Node::Array { state: s }
                        | Node::Object { state: s, .. } => *s = Some(state),
                        _ => return Err(fail("BUILD on a value that takes no state".into())),
                    }
                }
                b'p' => {
                    let key = self.line()?.parse().map_err(|_| fail("bad memo key".into()))?;
                    memo.insert(key, self.top().map_err(fail)?);
                }
                b'q' => {
                    let key = self.take(1)?[0].into();
                    memo.insert(key, self.top().map_err(fail)?);
                }
                b'r' => {
                    let key = self.take_len4()? as u64;
                    memo.insert(key, self.top().map_err(fail)?);
                }
                0x94 => {
                    let key = memo.len() as u64;
                    memo.insert(key, self.top().map_err(fail)?);
                }
                b'g' | b'h' | b'j' => {
                    let key: u64 = match op {
                        b'g' => self.line()?.parse().map_err(|_| fail("bad memo key".into()))?,
                        b'h' => self.take(1)?[0].into(),
                        _ => self.take_len4()? as u64,
                    };
                    let id =
                        *memo.get(&key).ok_or_else(|| fail(format!("memo key {key} was never stored")))?;
                    self.stack.push(id);
                }
                b'P' | b'Q' => return Err(fail("persistent ids are not supported".into())),
                0x82..=0x84 => {
                    return Err(fail("extension codes (copyreg registry) are not supported".into()));
                }
                0x97 | 0x98 => return Err(fail("out-of-band buffers are not supported".into())),
                _ => return Err(fail("unknown opcode".into())),
            }
        }
    }

    fn push(&mut self, node: Node) {
        self.nodes.push(node);
        self.stack.push(self.nodes.len() - 1);
    }

    fn pop(&mut self) -> Result<Id, String> {
        if self.marks.last().is_some_and(|&m| m >= self.stack.len()) {
            return Err("pop across a MARK".into());
        }
        self.stack.pop().ok_or_else(|| "stack underflow".into())
    }

    fn top(&self) -> Result<Id, String> {
        self.stack.last().copied().ok_or_else(|| "stack underflow".into())
    }

    fn pop_mark(&mut self) -> Result<Vec<Id>, String> {
        let mark = self.marks.pop().ok_or("no MARK on the stack")?;
        if mark > self.stack.len() {
            return Err("the values after a MARK were consumed".into());
        }
        Ok(self.stack.split_off(mark))
    }

    /// A copy of the argument tuple `id`, charged to the budget.
    fn arguments(&mut self, id: Id) -> Result<Vec<Id>, String> {
        let Node::Tuple(args) = &self.nodes[id] else { return Err("the arguments are not a tuple".into()) };
        spend(&mut self.budget, 1 + args.len())?;
        Ok(args.clone())
    }

    fn extend_list(&mut self, items: Vec<Id>) -> Result<(), String> {
        let target = self.top()?;
        match &mut self.nodes[target] {
            Node::List(v) => v.extend(items),
            _ => return Err("APPEND on a non-list".into()),
        }
        Ok(())
    }

    fn set_items(&mut self, items: Vec<(Id, Id)>) -> Result<(), String> {
        let target = self.top()?;
        match &mut self.nodes[target] {
            Node::Dict(v) => v.extend(items),
            _ => return Err("SETITEM on a non-dict".into()),
        }
        Ok(())
    }

    /// `callable(*args)`, interpreted: only the allowed globals can be called.
    fn call(&mut self, callable: Id, args: Vec<Id>) -> Result<Node, String> {
        let Node::Global { callable: kind, qualified } = self.nodes[callable].clone() else {
            return Err(format!("a {} is called; only allowed globals are", self.kind_name(callable)));
        };
        let arg =
            |i: usize| args.get(i).copied().ok_or_else(|| format!("{qualified} needs argument {}", i + 1));
        match kind {
            Callable::Reconstruct => Ok(Node::Array { state: None }),
            Callable::Scalar => Ok(Node::Scalar { dtype: arg(0)?, data: arg(1)? }),
            Callable::Dtype => match &self.nodes[arg(0)?] {
                Node::Str(name) => Ok(Node::Dtype { name: name.clone(), state: None }),
                Node::Str8(name) => Ok(Node::Dtype { name: latin1(name), state: None }),
                _ => Err("numpy.dtype's first argument is not a string".into()),
            },
            Callable::Reconstructor => self.new_object(arg(0)?, Vec::new()),
            Callable::Class => Ok(Node::Object { class: qualified, args, state: None }),
            Callable::ObjectClass => Ok(Node::Object { class: qualified, args: Vec::new(), state: None }),
            Callable::Encode => {
                let text = match &self.nodes[arg(0)?] {
                    Node::Str(text) => text.clone(),
                    Node::Str8(bytes) => latin1(bytes),
                    _ => return Err("_codecs.encode's first argument is not a string".into()),
                };
                let bytes: Option<Vec<u8>> = text.chars().map(|c| u8::try_from(u32::from(c)).ok()).collect();
                Ok(Node::Bytes(bytes.ok_or("_codecs.encode: a character past latin1")?))
            }
            Callable::NdarrayClass => Err("numpy.ndarray is called directly".into()),
        }
    }

    /// `cls.__new__(cls, *args)` for an allowed class.
    fn new_object(&mut self, class: Id, args: Vec<Id>) -> Result<Node, String> {
        match &self.nodes[class] {
            Node::Global { callable: Callable::Class | Callable::ObjectClass, qualified } => {
                Ok(Node::Object { class: qualified.clone(), args, state: None })
            }
            Node::Global { callable: Callable::NdarrayClass, .. } => Ok(Node::Array { state: None }),
            Node::Global { qualified, .. } => Err(format!("{qualified} is not a class")),
            _ => Err(format!("a {} is instantiated; only allowed classes are", self.kind_name(class))),
        }
    }

    fn kind_name(&self, id: Id) -> &'static str {
        match self.nodes[id] {
            Node::Tuple(_) => "tuple",
            Node::List(_) => "list",
            Node::Dict(_) => "dict",
            Node::Str(_) | Node::Str8(_) => "string",
            _ => "value",
        }
    }

    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.input.len()).ok_or_else(|| {
            format!("{n} bytes at offset {} run past the end ({} bytes)", self.at, self.input.len())
        })?;
        let out = &self.input[self.at..end];
        self.at = end;
        Ok(out)
    }

    fn take_len4(&mut self) -> Result<usize, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().unwrap()) as usize)
    }

    fn take_len8(&mut self) -> Result<usize, String> {
        let n = u64::from_le_bytes(self.take(8)?.try_into().unwrap());
        usize::try_from(n).map_err(|_| format!("length {n} does not fit in memory"))
    }

    fn text(&mut self, n: usize) -> Result<String, String> {
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| "a string is not UTF-8".into())
    }

    /// One text line (protocol 0 arguments), without its newline.
    fn line(&mut self) -> Result<String, String> {
        let rest = &self.input[self.at..];
        let n = rest.iter().position(|&b| b == b'\n').ok_or("a text argument has no newline")?;
        let line = latin1(&rest[..n]);
        self.at += n + 1;
        Ok(line)
    }

    // ---- the arena to values ----

    fn value(&self, id: Id, depth: usize, budget: &mut usize) -> Result<PyValue, String> {
        if depth > MAX_DEPTH {
            return Err(format!("values nest deeper than {MAX_DEPTH} (or refer to themselves)"));
        }
        spend(budget, 1)?;
        let list = |ids: &[Id], budget: &mut usize| -> Result<Vec<PyValue>, String> {
            ids.iter().map(|&i| self.value(i, depth + 1, budget)).collect()
        };
        Ok(match &self.nodes[id] {
            Node::None => PyValue::None,
            Node::Bool(b) => PyValue::Bool(*b),
            Node::Int(i) => PyValue::Int(*i),
            Node::BigInt(b) => {
                spend(budget, b.len())?;
                PyValue::BigInt(b.clone())
            }
            Node::Float(f) => PyValue::Float(*f),
            Node::Str(s) => {
                spend(budget, s.len())?;
                PyValue::Str(s.clone())
            }
            Node::Str8(b) => {
                spend(budget, 2 * b.len())?;
                PyValue::Str(latin1(b))
            }
            Node::Bytes(b) => {
                spend(budget, b.len())?;
                PyValue::Bytes(b.clone())
            }
            Node::List(v) => PyValue::List(list(v, budget)?),
            Node::Tuple(v) => PyValue::Tuple(list(v, budget)?),
            Node::Set(v) => PyValue::Set(list(v, budget)?),
            Node::Dict(v) => PyValue::Dict(
                v.iter()
                    .map(|&(k, x)| Ok((self.value(k, depth + 1, budget)?, self.value(x, depth + 1, budget)?)))
                    .collect::<Result<_, String>>()?,
            ),
            Node::Global { qualified, .. } => {
                PyValue::Object { class: qualified.clone(), args: Vec::new(), state: None }
            }
            Node::Dtype { name, .. } => PyValue::Str(self.descr(id).unwrap_or_else(|_| name.clone())),
            Node::Array { state } => {
                let state = state.ok_or("an ndarray without its state")?;
                match self.array(state, budget)? {
                    Some(array) => PyValue::Array(array),
                    None => PyValue::Unreadable("an ndarray of Python objects".into()),
                }
            }
            Node::Scalar { dtype, data } => {
                let descr = self.descr(*dtype)?;
                let bytes = self.bytes(*data)?;
                spend(budget, 8 * bytes.len())?;
                PyValue::Array(decode_array_data(&descr, Vec::new(), false, bytes)?)
            }
            Node::Object { class, args, state } => PyValue::Object {
                class: class.clone(),
                args: list(args, budget)?,
                state: match state {
                    Some(s) => Some(Box::new(self.value(*s, depth + 1, budget)?)),
                    None => None,
                },
            },
        })
    }

    /// An ndarray from its state `(version, shape, dtype, is_fortran, data)` (or the
    /// versionless 4-tuple of old pickles).
    /// `None` for an object array, which is not read.
    fn array(&self, state: Id, budget: &mut usize) -> Result<Option<AnyArray>, String> {
        let Node::Tuple(items) = &self.nodes[state] else {
            return Err("an ndarray's state is not a tuple".into());
        };
        let items = match items.len() {
            5 => &items[1..],
            4 => &items[..],
            n => return Err(format!("an ndarray's state has {n} items, not 4 or 5")),
        };
        let Node::Tuple(dims) = &self.nodes[items[0]] else {
            return Err("an ndarray's shape is not a tuple".into());
        };
        let shape = dims
            .iter()
            .map(|&d| match self.nodes[d] {
                Node::Int(n) => usize::try_from(n).map_err(|_| format!("negative dimension {n}")),
                _ => Err("a dimension is not an integer".into()),
            })
            .collect::<Result<Vec<_>, _>>()?;
        let descr = self.descr(items[1])?;
        let fortran = match self.nodes[items[2]] {
            Node::Bool(b) => b,
            Node::Int(i) => i != 0,
            _ => return Err("an ndarray's order flag is not a bool".into()),
        };
        if descr[1..].starts_with('O') {
            return Ok(None);
        }
        let data = self.bytes(items[3])?;
        // Decoding widens at most 8 times (bools to f64 later): charge that up front.
        spend(budget, 8 * data.len())?;
        decode_array_data(&descr, shape, fortran, data).map(Some)
    }

    /// A dtype node as an npy `descr`: byte order from its state, then the name's kind and
    /// size (`'f8'`, `'<U7'`).
    fn descr(&self, id: Id) -> Result<String, String> {
        let Node::Dtype { name, state } = &self.nodes[id] else {
            return Err("a dtype is not a numpy.dtype".into());
        };
        let order = match state.map(|s| &self.nodes[s]) {
            Some(Node::Tuple(items)) => match items.get(1).map(|&i| &self.nodes[i]) {
                Some(Node::Str(o)) => o.clone(),
                Some(Node::Str8(o)) => latin1(o),
                _ => "|".to_owned(),
            },
            _ => "|".to_owned(),
        };
        let order = if order == ">" { ">" } else { "<" };
        let name = name.trim_start_matches(['<', '>', '|', '=']);
        Ok(format!("{order}{name}"))
    }

    fn bytes(&self, id: Id) -> Result<&[u8], String> {
        match &self.nodes[id] {
            Node::Bytes(b) | Node::Str8(b) => Ok(b),
            Node::Str(s) => Ok(s.as_bytes()),
            _ => Err("an ndarray's data is not a byte string".into()),
        }
    }
}

fn spend(budget: &mut usize, units: usize) -> Result<(), String> {
    *budget = budget.checked_sub(units).ok_or_else(|| {
        format!(
            "the values would take more than {BUDGET_FACTOR} times the file's size (shared objects repeated)"
        )
    })?;
    Ok(())
}

/// The global `module.name`, if allowed; the refusal names it.
fn global(module: &str, name: &str) -> Result<Node, String> {
    let allowed = ALLOWED.iter().any(|&(m, n)| m == module && (n == name || n == "*"));
    let qualified = format!("{module}.{name}");
    if !allowed {
        return Err(format!(
            "global '{qualified}' is not allowed: desal reads numpy arrays, chumpy objects and scipy CSC matrices from a pickle and never runs pickled code"
        ));
    }
    let callable = match (module, name) {
        (_, "_reconstruct") => Callable::Reconstruct,
        (_, "scalar") => Callable::Scalar,
        ("numpy", "ndarray") => Callable::NdarrayClass,
        ("numpy", "dtype") => Callable::Dtype,
        (_, "_reconstructor") => Callable::Reconstructor,
        (_, "object") => Callable::ObjectClass,
        ("_codecs", _) => Callable::Encode,
        _ => Callable::Class,
    };
    Ok(Node::Global { callable, qualified })
}

fn long_node(bytes: Vec<u8>) -> Node {
    if bytes.is_empty() {
        return Node::Int(0);
    }
    if bytes.len() <= 8 {
        let fill = if bytes[bytes.len() - 1] & 0x80 != 0 { 0xff } else { 0 };
        let mut wide = [fill; 8];
        wide[..bytes.len()].copy_from_slice(&bytes);
        return Node::Int(i64::from_le_bytes(wide));
    }
    Node::BigInt(bytes)
}

fn pairs(items: Vec<Id>) -> Result<Vec<(Id, Id)>, String> {
    if !items.len().is_multiple_of(2) {
        return Err("a dict needs key/value pairs".into());
    }
    Ok(items.chunks_exact(2).map(|c| (c[0], c[1])).collect())
}

fn latin1(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| char::from(b)).collect()
}

/// A protocol-0 string literal (`'abc'` or `"abc"`, Python escapes) as bytes.
fn unquote(line: &str) -> Option<Vec<u8>> {
    let inner = line
        .strip_prefix('\'')
        .and_then(|l| l.strip_suffix('\''))
        .or_else(|| line.strip_prefix('"').and_then(|l| l.strip_suffix('"')))?;
    let chars: Vec<char> = inner.chars().collect();
    let mut out = Vec::with_capacity(chars.len());
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        i += 1;
        if c != '\\' {
            out.push(u8::try_from(u32::from(c)).ok()?);
            continue;
        }
        let e = *chars.get(i)?;
        i += 1;
        match e {
            'n' => out.push(b'\n'),
            't' => out.push(b'\t'),
            'r' => out.push(b'\r'),
            '\\' | '\'' | '"' => out.push(e as u8),
            'x' => {
                let hex: String = chars.get(i..i + 2)?.iter().collect();
                out.push(u8::from_str_radix(&hex, 16).ok()?);
                i += 2;
            }
            _ => return None,
        }
    }
    Some(out)
}

/// Python's `raw-unicode-escape` (protocol 0 `UNICODE`): `\uXXXX` and `\UXXXXXXXX`.
fn raw_unicode_unescape(line: &str) -> Option<String> {
    let mut out = String::new();
    let mut rest = line;
    while let Some(p) = rest.find('\\') {
        out.push_str(&rest[..p]);
        let after = &rest[p + 1..];
        let width = match after.chars().next() {
            Some('u') => 4,
            Some('U') => 8,
            _ => {
                out.push('\\');
                rest = after;
                continue;
            }
        };
        let hex = after.get(1..1 + width)?;
        out.push(char::from_u32(u32::from_str_radix(hex, 16).ok()?)?);
        rest = &after[1 + width..];
    }
    out.push_str(rest);
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::npz::AnyData;

    fn state_of<'a>(value: &'a PyValue, key: &str) -> (&'a str, &'a PyValue) {
        match value.get(key) {
            Some(PyValue::Object { class, state: Some(state), .. }) => (class, state),
            other => panic!("{key}: not an object with state: {other:?}"),
        }
    }

    fn array(value: Option<&PyValue>) -> &AnyArray {
        match value {
            Some(PyValue::Array(a)) => a,
            other => panic!("not an array: {other:?}"),
        }
    }

    /// What Python 3 writes (`make_pickles.py`): numpy 2 arrays (Fortran order read back in
    /// C order), a scipy CSC matrix and a chumpy-like object with their state dicts, bytes
    /// through `_codecs.encode` at protocol 2, big integers. Protocols 2 and 4 agree.
    #[test]
    fn python3_pickles() {
        for bytes in [
            &include_bytes!("../tests/fixtures/py3_protocol2.pkl")[..],
            include_bytes!("../tests/fixtures/py3_protocol4.pkl"),
        ] {
            let value = unpickle(bytes).unwrap();
            let (class, ch) = state_of(&value, "v_template");
            assert_eq!(class, "chumpy.ch.Ch");
            let x = array(ch.get("x"));
            assert_eq!(
                (x.shape.as_slice(), &x.data),
                (&[2, 3][..], &AnyData::F64(vec![0.0, 1.0, 2.0, 3.0, 4.5, -5.0]))
            );
            assert_eq!(array(value.get("f")).data, AnyData::U32(vec![0, 1, 1]));
            assert_eq!(array(value.get("weights")).data, AnyData::F32(vec![1.0, 0.0, 0.25, 0.75]));
            let (class, csc) = state_of(&value, "J_regressor");
            assert_eq!(class, "scipy.sparse._csc.csc_matrix");
            assert_eq!(array(csc.get("data")).data, AnyData::F64(vec![0.5, 0.5, 1.0]));
            assert_eq!(array(csc.get("indptr")).data.to_i64().unwrap(), [0, 1, 3]);
            assert_eq!(csc.get("_shape"), Some(&PyValue::Tuple(vec![PyValue::Int(2), PyValue::Int(2)])));
            assert_eq!(value.get("bs_style"), Some(&PyValue::Str("lbs".into())));
            assert_eq!(array(value.get("flags")).data, AnyData::Bool(vec![true, false]));
            assert_eq!(value.get("scale"), Some(&PyValue::Float(1.5)));
            assert_eq!(value.get("count"), Some(&PyValue::Int(1 << 40)));
        }
    }

    /// The Python 2 layout of SMPL-family files: `copy_reg._reconstructor`, array data in
    /// `BINSTRING`s, and a dtype memoised *before* its `BUILD` and reused by `BINGET`,
    /// which must see the built dtype (the arena shares objects as Python does).
    #[test]
    fn python2_chumpy_pickle() {
        let value = unpickle(include_bytes!("../tests/fixtures/py2_chumpy.pkl")).unwrap();
        let (class, ch) = state_of(&value, "v_template");
        assert_eq!(class, "chumpy.ch.Ch");
        assert_eq!(array(ch.get("x")).data, AnyData::F64(vec![0.0, 1.0, 2.0, 3.0, 4.5, -5.0]));
        assert_eq!(array(value.get("J")).data, AnyData::F64(vec![1.0, 2.0]));
        assert_eq!(value.get("bs_style"), Some(&PyValue::Str("lbs".into())));
    }

    /// The classic exploit — `os.system` called by REDUCE — is refused at the GLOBAL,
    /// naming it, before anything is called; so are builtins.eval and a STACK_GLOBAL.
    #[test]
    fn other_globals_are_refused_by_name() {
        let exploit = b"\x80\x02cos\nsystem\nX\x04\x00\x00\x00echo\x85R.";
        let err = unpickle(exploit).unwrap_err();
        assert!(err.contains("global 'os.system' is not allowed"), "{err}");
        let err = unpickle(b"\x80\x02cbuiltins\neval\n.").unwrap_err();
        assert!(err.contains("'builtins.eval'"), "{err}");
        let stack_global = b"\x80\x04\x8c\x08builtins\x8c\x04exec\x93.";
        assert!(unpickle(stack_global).unwrap_err().contains("'builtins.exec'"));
        // An allowed global that is not a callable of its kind is still not called.
        assert!(unpickle(b"\x80\x02cnumpy\nndarray\n)R.").is_err());
    }

    /// Truncations and single-byte corruptions are errors or values, never panics.
    #[test]
    fn damaged_pickles_never_panic() {
        let good = include_bytes!("../tests/fixtures/py3_protocol2.pkl");
        for len in 0..good.len() {
            assert!(unpickle(&good[..len]).is_err(), "truncated to {len}");
        }
        for at in 0..good.len() {
            let mut bad = good.to_vec();
            bad[at] ^= 0x5a;
            let _ = unpickle(&bad);
        }
    }

    /// Found by desal-fuzz: TUPLE2 taking a value from below a MARK, then the MARK's
    /// pop, once split the stack past its end.
    #[test]
    fn a_tuple_across_a_mark_is_refused() {
        let err = unpickle(b"\x80\x02K\x01(K\x02\x86t.").unwrap_err();
        assert!(err.contains("across a MARK"), "{err}");
    }

    /// One memoised tuple of 100 000 items passed to 100 000 calls would copy 10^10
    /// ids: refused by the budget, quickly.
    #[test]
    fn repeated_calls_with_a_large_tuple_are_bounded() {
        let mut bytes = b"\x80\x02cchumpy.ch\nCh\nq\x00(".to_vec();
        bytes.extend(std::iter::repeat_n(b'N', 100_000));
        bytes.extend_from_slice(b"tq\x01(");
        for _ in 0..100_000 {
            bytes.extend_from_slice(b"h\x00h\x01R0");
        }
        bytes.extend_from_slice(b"1N.");
        let start = std::time::Instant::now();
        let err = unpickle(&bytes).unwrap_err();
        assert!(err.contains("times the file's size"), "{err}");
        assert!(start.elapsed().as_secs() < 5);
    }

    /// A list appended to itself, and a chain of lists each holding the previous one
    /// twice (2^k copies from k steps), are refused instead of exhausting memory.
    #[test]
    fn cycles_and_doubling_chains_are_bounded() {
        let cycle = b"\x80\x02]q\x00h\x00a.";
        assert!(unpickle(cycle).unwrap_err().contains("nest deeper"));
        let mut chain = b"\x80\x02]q\x00".to_vec();
        for k in 0..60u8 {
            // [prev, prev], memoised as k + 1.
            chain.extend_from_slice(&[b'(', b'h', k, b'h', k, b'l', b'q', k + 1]);
        }
        chain.push(b'.');
        let err = unpickle(&chain).unwrap_err();
        assert!(err.contains("times the file's size"), "{err}");
    }
}
