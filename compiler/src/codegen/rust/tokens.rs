//! Token builders of the Rust backend: float literals of the table's
//! precision, arrays and matrices, membership constructors and premise
//! expressions.

use crate::tables::sym::{Func, Sym};
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote};
use tsf_lang::spec::{Precision, SetShape};

/// A float literal of the table's precision (shortest round-trip form;
/// negatives as a unary minus; infinities as the type's constant).
pub(super) fn float(v: f64, prec: Precision) -> TokenStream {
    let ty = real_ty(prec);
    if v.is_infinite() {
        return if v > 0.0 {
            quote!(#ty::INFINITY)
        } else {
            quote!(#ty::NEG_INFINITY)
        };
    }
    if v.is_nan() {
        return quote!(#ty::NAN);
    }
    let lit = match prec {
        Precision::F64 => Literal::f64_unsuffixed(v.abs()),
        Precision::F32 => Literal::f32_unsuffixed((v as f32).abs()),
    };
    if v.is_sign_negative() && v != 0.0 {
        quote!(-#lit)
    } else {
        quote!(#lit)
    }
}

pub(super) fn real_ty(prec: Precision) -> Ident {
    Ident::new(
        if prec == Precision::F32 { "f32" } else { "f64" },
        Span::call_site(),
    )
}

pub(super) fn array(values: &[f64], prec: Precision) -> TokenStream {
    let items = values.iter().map(|v| float(*v, prec));
    quote!([#(#items),*])
}

pub(super) fn matrix(rows: &[Vec<f64>], prec: Precision) -> TokenStream {
    let items = rows.iter().map(|r| array(r, prec));
    quote!([#(#items),*])
}

pub(super) fn membership(s: &SetShape, prec: Precision) -> TokenStream {
    let f = |v: f64| float(v, prec);
    match *s {
        SetShape::Tri(a, b, c) => {
            let (a, b, c) = (f(a), f(b), f(c));
            quote!(Membership::Tri { a: #a, b: #b, c: #c })
        }
        SetShape::Trap(a, b, c, d) => {
            let (a, b, c, d) = (f(a), f(b), f(c), f(d));
            quote!(Membership::Trap { a: #a, b: #b, c: #c, d: #d })
        }
        SetShape::Gauss(center, sigma) => {
            let (c, s) = (f(center), f(sigma));
            quote!(Membership::Gauss { center: #c, sigma: #s })
        }
        SetShape::Sigmoid(slope, center) => {
            let (k, c) = (f(slope), f(center));
            quote!(Membership::Sigmoid { slope: #k, center: #c })
        }
    }
}

/// Scalar code for a premise expression; `x` is the state array. Parentheses
/// only where precedence needs them (the tree's grouping is kept exactly, so
/// the C generator's code performs the same operations in the same order).
pub(super) fn sym(s: &Sym, prec: Precision) -> TokenStream {
    sym_in(s, prec, 0)
}

/// Binding strength of a node: sums 1, products 2, negation 3, atoms 4.
fn strength(s: &Sym) -> u8 {
    match s {
        Sym::Add(..) => 1,
        Sym::Mul(..) | Sym::Div(..) => 2,
        Sym::Neg(_) => 3,
        Sym::Const(v) if *v < 0.0 => 3,
        _ => 4,
    }
}

fn sym_in(s: &Sym, prec: Precision, parent: u8) -> TokenStream {
    let inner = match s {
        Sym::Const(v) => float(*v, prec),
        Sym::X(k) => {
            let k = Literal::usize_unsuffixed(*k);
            quote!(x[#k])
        }
        Sym::Add(a, b) => {
            let (a, b) = (sym_in(a, prec, 1), sym_in(b, prec, 2));
            quote!(#a + #b)
        }
        Sym::Mul(a, b) => {
            let (a, b) = (sym_in(a, prec, 2), sym_in(b, prec, 3));
            quote!(#a * #b)
        }
        Sym::Div(a, b) => {
            let (a, b) = (sym_in(a, prec, 2), sym_in(b, prec, 3));
            quote!(#a / #b)
        }
        Sym::Neg(a) => {
            let a = sym_in(a, prec, 4);
            quote!(-#a)
        }
        Sym::Call(f, a) => {
            let a = sym_in(a, prec, 0);
            let name = match f {
                Func::Abs => format_ident!("abs"),
                other => format_ident!("{}", other.name()),
            };
            quote!(Real::#name(#a))
        }
    };
    if strength(s) < parent {
        quote!((#inner))
    } else {
        inner
    }
}
