//! Run-time choice of instruction set.
//!
//! The kernels are compiled twice: for the baseline x86-64 (SSE2), and with AVX2 and FMA
//! enabled, chosen at run time when the processor has them. The code is the same; the AVX
//! encoding's three-operand instructions remove the register copies that SSE2's two-operand
//! form needs (a large share of the instructions of `contact_function`), and the lanes
//! of the batched path fit one 256-bit register. Other architectures get the portable build.

/// Defines `$name` as a dispatcher to `$body`, compiled with AVX2 + FMA when the processor
/// has them. The body (`=> fused $body`) takes a `const FMA: bool` telling it whether
/// fused multiply–adds are hardware instructions (true in the AVX2 + FMA build); without
/// them `mul_add` would be a slow library call, so the portable build keeps `a * b + c`.
macro_rules! multiversion {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty => fused $body:ident;) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2,fma")]
                fn with_avx2($($arg: $ty),*) -> $ret {
                    $crate::dispatch::align_frame();
                    $body::<true>($($arg),*)
                }
                if $crate::dispatch::has_avx2_fma() {
                    // SAFETY: `with_avx2` only needs AVX2 and FMA, and the processor was just
                    // checked to have both.
                    return unsafe { with_avx2($($arg),*) };
                }
            }
            $body::<false>($($arg),*)
        }
    };
}
pub(crate) use multiversion;

/// Defines `$name::<FMA>` as a function of its own (not inlined) that runs
/// `$body::<FMA>`. A function of its own is compiled without its caller's AVX2 and FMA
/// features, and its blends and fused multiply–adds would be calls; with `FMA` (the caller
/// is the AVX2 + FMA build of a dispatched function) it therefore hands over to a twin
/// compiled with them.
macro_rules! out_of_line {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty => $body:ident;) => {
        $(#[$meta])*
        #[inline(never)]
        $vis fn $name<const FMA: bool>($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if FMA {
                #[target_feature(enable = "avx2,fma")]
                fn with_avx2($($arg: $ty),*) -> $ret {
                    $crate::dispatch::align_frame();
                    $body::<true>($($arg),*)
                }
                // SAFETY: `FMA` is true only in the AVX2 + FMA build of a dispatched
                // function, after the processor was checked to have both.
                return unsafe { with_avx2($($arg),*) };
            }
            $body::<FMA>($($arg),*)
        }
    };
}
pub(crate) use out_of_line;

/// Whether the processor has AVX2 and FMA (cached by the standard library after the first
/// call).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn has_avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// A 32-byte-aligned local whose address escapes, so that the function this is inlined into
/// realigns its stack frame to 32 bytes (two instructions).
///
/// The AVX2 builds spill 256-bit registers; with the ABI's 16-byte stack alignment the
/// compiler places those spills at 16-byte offsets with unaligned moves, and where the
/// caller's stack pointer put one across a page boundary every call paid for split loads and
/// stores. With the stack shifted 32 bytes at a time before the bench `contact`'s loops, the
/// contact function and the batch ran markedly slower at some shifts (and so in some runs,
/// wherever address-space randomisation put the stack); with the frame realigned every
/// shift runs at the same speed.
#[repr(align(32))]
struct Aligned(#[allow(dead_code)] [u8; 32]); // Only its alignment is used.

#[inline(always)]
pub(crate) fn align_frame() {
    let mut anchor = Aligned([0; 32]);
    core::hint::black_box(&mut anchor);
}
