//! Every shader of the terrain keeps its branches off conditions that read uniforms alone.
//!
//! Mesa 22's lavapipe (the software GPU this project is measured on) looks for `if`s whose
//! condition depends only on uniform values, inlines those values into the shader and compiles
//! it again each time its pipeline is bound: 3-4 ms a frame when the water's switches were such
//! branches. The shaders use `select`s or flat varyings instead (see `lighting.wgsl`); this test
//! parses every program as its pipeline builds it and fails on any such branch.

use naga::{AddressSpace, Block, Expression, Function, Handle, Module, Statement};

/// Every program the renderer builds, as its pipeline is built from it.
const PROGRAMS: [(&str, &str); 9] = [
    ("course land", super::land::SHADER),
    ("course sky", super::sky::COURSE_SHADER),
    ("course water", super::water::SHADER),
    ("course grid", super::course::GRID_SHADER),
    ("shadow map", super::shadow::SHADER),
    ("light map", super::light_map::SHADER),
    ("modern land", super::modern::LAND_SHADER),
    ("modern sky", super::sky::MODERN_SHADER),
    ("sea", super::sea::SHADER),
];

/// What an expression's value depends on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Source {
    /// Constants alone.
    Constant,
    /// Uniforms (and constants).
    Uniform,
    /// Anything that may differ between invocations, or that this check does not follow
    /// (function arguments, local variables, textures, calls).
    Varying,
}

fn source_of(module: &Module, function: &Function, expression: Handle<Expression>) -> Source {
    let of = |e: Handle<Expression>| source_of(module, function, e);
    let all = |list: &[Handle<Expression>]| list.iter().map(|&e| of(e)).max().unwrap_or(Source::Constant);
    match function.expressions[expression] {
        Expression::Literal(_)
        | Expression::Constant(_)
        | Expression::Override(_)
        | Expression::ZeroValue(_) => Source::Constant,
        Expression::GlobalVariable(global) => match module.global_variables[global].space {
            AddressSpace::Uniform => Source::Uniform,
            _ => Source::Varying,
        },
        Expression::Load { pointer } => of(pointer),
        Expression::Access { base, index } => all(&[base, index]),
        Expression::AccessIndex { base, .. } => of(base),
        Expression::Splat { value, .. } => of(value),
        Expression::Swizzle { vector, .. } => of(vector),
        Expression::Unary { expr, .. } | Expression::As { expr, .. } => of(expr),
        Expression::Relational { argument, .. } => of(argument),
        Expression::Binary { left, right, .. } => all(&[left, right]),
        Expression::Select { condition, accept, reject } => all(&[condition, accept, reject]),
        Expression::Compose { ref components, .. } => all(components),
        Expression::Math { arg, arg1, arg2, arg3, .. } => {
            let args: Vec<_> = [Some(arg), arg1, arg2, arg3].into_iter().flatten().collect();
            all(&args)
        }
        _ => Source::Varying,
    }
}

/// The names of the functions in `block` (and the blocks inside it) that branch on uniforms
/// alone.
fn uniform_branches(module: &Module, function: &Function, block: &Block, found: &mut Vec<String>) {
    for statement in block.iter() {
        // The statement's own test: an if's condition, a switch's selector, a loop's exit test
        // (lavapipe inlines the uniforms of all three).
        let test = match statement {
            Statement::If { condition, .. } => Some(*condition),
            Statement::Switch { selector, .. } => Some(*selector),
            Statement::Loop { break_if, .. } => *break_if,
            _ => None,
        };
        if test.is_some_and(|test| source_of(module, function, test) == Source::Uniform) {
            found.push(function.name.clone().unwrap_or_default());
        }
        match statement {
            Statement::If { accept, reject, .. } => {
                uniform_branches(module, function, accept, found);
                uniform_branches(module, function, reject, found);
            }
            Statement::Switch { cases, .. } => {
                for case in cases {
                    uniform_branches(module, function, &case.body, found);
                }
            }
            Statement::Loop { body, continuing, .. } => {
                uniform_branches(module, function, body, found);
                uniform_branches(module, function, continuing, found);
            }
            Statement::Block(inner) => uniform_branches(module, function, inner, found),
            _ => {}
        }
    }
}

fn branches_on_uniforms(source: &str) -> Vec<String> {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|error| panic!("{}", error.emit_to_string(source)));
    let mut found = Vec::new();
    let functions =
        module.functions.iter().map(|(_, f)| f).chain(module.entry_points.iter().map(|e| &e.function));
    for function in functions {
        uniform_branches(&module, function, &function.body, &mut found);
    }
    found
}

#[test]
fn no_program_branches_on_uniforms_alone() {
    for (name, source) in PROGRAMS {
        let found = branches_on_uniforms(source);
        assert!(found.is_empty(), "the {name} program branches on uniforms alone in {found:?}");
    }
}

#[test]
fn the_check_finds_such_branches() {
    let source = "struct S { on: f32, x: f32 }
        @group(0) @binding(0) var<uniform> s: S;
        fn lit(v: f32) -> f32 {
            if (s.on > 0.5 && s.x < 2.0) { return v * 2.0; }
            if (v > s.x) { return v; }
            return select(v, 0.0, s.on > 0.5);
        }
        fn spin(v: f32) -> f32 {
            var y = v;
            loop {
                y = y * 0.5;
                continuing { break if s.x > 1.0; }
            }
            return y;
        }
        @fragment fn main(@location(0) v: f32) -> @location(0) vec4<f32> {
            var y = lit(v) + spin(v);
            if (s.x > 1.0) { y = 0.0; }
            return vec4<f32>(y);
        }";
    assert_eq!(branches_on_uniforms(source), ["lit", "spin", "main"]);
}
