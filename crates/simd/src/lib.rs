//! # ellipack-simd — four `f64` lanes and one run-time dispatch
//!
//! The SIMD layer of the ellipack workspace, shared by `pw85` (the contact function) and
//! `implicit-packing` (the packing model):
//!
//! - [`has_avx2_fma`] — one cached detection of AVX2 and FMA;
//! - [`multiversion!`] — a function compiled for baseline x86-64 and again with AVX2 + FMA,
//!   the build chosen per call from the cached detection;
//! - [`F64x4`] and [`Mask4`] (x86-64) — four `f64` lanes in one 256-bit register;
//! - [`dot`], [`step_dot`], [`norm_inf`], [`axpy_dot`] — reductions over long slices with independent
//!   partial results.
//!
//! Why compile twice: the kernels above are chains of dependent 3×3 products and short
//! polynomial evaluations. The AVX encoding's three-operand instructions remove the register
//! copies that SSE2's two-operand form needs, and four lanes fit one register. The arithmetic
//! is the same in both builds: Rust never contracts `a * b + c` into a fused multiply–add, so
//! a kernel written with plain operators gives the same bits in both; a kernel that wants
//! hardware FMA asks for it explicitly (the `fused` form of [`multiversion!`]).
//!
//! ```
//! /// Σ aᵢ bᵢ, fused where the hardware fuses.
//! #[inline(always)]
//! fn dot4<const FMA: bool>(a: &[f64; 4], b: &[f64; 4]) -> f64 {
//!     let mut s = 0.0;
//!     for k in 0..4 {
//!         s = if FMA { a[k].mul_add(b[k], s) } else { s + a[k] * b[k] };
//!     }
//!     s
//! }
//!
//! simd::multiversion! {
//!     /// [`dot4`] in the build the processor allows.
//!     pub fn dot(a: &[f64; 4], b: &[f64; 4]) -> f64 => fused dot4;
//! }
//!
//! assert_eq!(dot(&[1.0, 2.0, 3.0, 4.0], &[1.0; 4]), 10.0);
//! ```
//!
//! # Soundness
//! An [`F64x4`] or [`Mask4`] is created only by `unsafe` constructors whose contract is that
//! the processor has AVX2 and FMA (in practice: inside the AVX2 + FMA build of a function
//! defined with [`multiversion!`]). A value that exists is therefore proof that its
//! operations may run, and they are safe to call.
#![deny(missing_docs)]
#![no_std]

extern crate std;

use core::sync::atomic::{AtomicU8, Ordering};

#[cfg(target_arch = "x86_64")]
mod f64x4;
mod reduce;
#[cfg(target_arch = "x86_64")]
pub use f64x4::{F64x4, Mask4};
pub use reduce::{axpy_dot, dot, norm_inf, step_dot};

/// The environment variable that, set to `1`, makes [`has_avx2_fma`] answer `false`: the
/// portable build then runs on every x86-64 processor, for tests and benches of that build.
pub const DISABLE_VARIABLE: &str = "ELLIPACK_DISABLE_AVX2";

/// 0: not yet detected; 1: absent (or disabled); 2: present.
static DETECTED: AtomicU8 = AtomicU8::new(0);

/// Whether the processor has AVX2 and FMA, and [`DISABLE_VARIABLE`] does not ask for the
/// portable build.
///
/// The first call detects; later calls read one cached byte.
#[inline(always)]
pub fn has_avx2_fma() -> bool {
    match DETECTED.load(Ordering::Relaxed) {
        2 => true,
        1 => false,
        _ => detect(),
    }
}

#[cold]
#[inline(never)]
fn detect() -> bool {
    let disabled = std::env::var_os(DISABLE_VARIABLE).is_some_and(|v| v == "1");
    let present = !disabled && processor_has_avx2_fma();
    DETECTED.store(if present { 2 } else { 1 }, Ordering::Relaxed);
    present
}

#[cfg(target_arch = "x86_64")]
fn processor_has_avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

#[cfg(not(target_arch = "x86_64"))]
fn processor_has_avx2_fma() -> bool {
    false
}

/// Defines or calls a function compiled for baseline x86-64 and with AVX2 + FMA, and runs the
/// second where [`has_avx2_fma`] says it may. On other architectures only the portable build
/// exists.
///
/// Three forms:
///
/// - `multiversion! { $(#[attr])* vis fn name(args) -> Ret => fused body; }` defines `name`,
///   which runs `body::<true>(args)` in the AVX2 + FMA build and `body::<false>(args)`
///   otherwise. The `const FMA: bool` tells `body` whether fused multiply–adds are hardware
///   instructions; without them `f64::mul_add` is a slow library call, so the portable build
///   keeps `a * b + c`.
/// - `multiversion! { $(#[attr])* vis fn name(args) -> Ret => out_of_line body; }` defines
///   `name::<FMA>`, a function of its own (never inlined) running `body::<FMA>`. A function
///   of its own is compiled without its caller's target features, so its vector code would
///   become calls; with `FMA` (the caller is an AVX2 + FMA build) it hands over to a twin
///   compiled with them.
/// - `multiversion!(call f::<N>(args: Types) -> Ret)`, as the tail expression of a function
///   generic over `const N: usize`, runs `f::<N>(args)` in the build the processor allows.
///   `f` and what it calls on its hot path must be `#[inline(always)]` to be compiled with
///   the caller's instruction set.
#[macro_export]
macro_rules! multiversion {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty => fused $body:ident;) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2,fma")]
                fn with_avx2($($arg: $ty),*) -> $ret {
                    $body::<true>($($arg),*)
                }
                if $crate::has_avx2_fma() {
                    // SAFETY: `with_avx2` only needs AVX2 and FMA, and the processor has both.
                    return unsafe { with_avx2($($arg),*) };
                }
            }
            $body::<false>($($arg),*)
        }
    };
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty => out_of_line $body:ident;) => {
        $(#[$meta])*
        #[inline(never)]
        $vis fn $name<const FMA: bool>($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if FMA {
                #[target_feature(enable = "avx2,fma")]
                fn with_avx2($($arg: $ty),*) -> $ret {
                    $body::<true>($($arg),*)
                }
                // SAFETY: `FMA` is true only in the AVX2 + FMA build of a dispatched
                // function, which runs only where the processor has both.
                return unsafe { with_avx2($($arg),*) };
            }
            $body::<FMA>($($arg),*)
        }
    };
    (call $f:ident::<$n:ident>($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty) => {{
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "avx2,fma")]
            fn with_avx2<const $n: usize>($($arg: $ty),*) -> $ret {
                $f::<$n>($($arg),*)
            }
            if $crate::has_avx2_fma() {
                // SAFETY: `with_avx2` only needs AVX2 and FMA, and the processor has both.
                return unsafe { with_avx2::<$n>($($arg),*) };
            }
        }
        $f::<$n>($($arg),*)
    }};
}

/// Trait methods that a type has as inherent methods of the same name and meaning, written
/// inside the trait's `impl`: `inherent_methods!(Type: name(args) -> Output, ...)` defines
/// each `fn name(self, args: Self) -> Output` as `Type::name(self, args)`, `#[inline(always)]`
/// so that a lane type's method is its one instruction.
#[macro_export]
macro_rules! inherent_methods {
    ($ty:ident: $($name:ident($($arg:ident),*) -> $out:ty),* $(,)?) => {
        $(
            #[inline(always)]
            fn $name(self $(, $arg: Self)*) -> $out {
                $ty::$name(self $(, $arg)*)
            }
        )*
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[inline(always)]
    fn sum_of_products<const FMA: bool>(a: &[f64; 4], b: &[f64; 4]) -> (f64, bool) {
        let mut s = 0.0;
        for k in 0..4 {
            s = if FMA {
                a[k].mul_add(b[k], s)
            } else {
                s + a[k] * b[k]
            };
        }
        (s, FMA)
    }

    multiversion! {
        fn dispatched(a: &[f64; 4], b: &[f64; 4]) -> (f64, bool) => fused sum_of_products;
    }

    #[test]
    fn the_dispatch_follows_the_detection() {
        let (s, fused) = dispatched(&[1.0, 2.0, 3.0, 4.0], &[1.0, 1.0, 1.0, 1.0]);
        assert_eq!(s, 10.0);
        assert_eq!(fused, has_avx2_fma());
        // Cached: the second answer is the first.
        assert_eq!(has_avx2_fma(), has_avx2_fma());
    }

    #[inline(always)]
    fn norm2<const N: usize>(x: &[f64; N]) -> f64 {
        x.iter().map(|v| v * v).sum()
    }

    fn norm2_dispatched<const N: usize>(x: &[f64; N]) -> f64 {
        multiversion!(call norm2::<N>(x: &[f64; N]) -> f64)
    }

    #[test]
    fn the_call_form_computes_the_same_value() {
        assert_eq!(norm2_dispatched(&[3.0, 4.0]), 25.0);
        assert_eq!(norm2_dispatched(&[1.0, 2.0, 2.0]), 9.0);
    }
}
