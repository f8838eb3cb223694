//! Independent references for the model-factor tests: double-double
//! arithmetic (≈ 32 significant digits) with exp, expm1, sin(πx), cos(πx),
//! and tanh-sinh quadrature. Nothing here calls the code under test.

#![allow(dead_code)]

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A double-double number hi + lo, |lo| ≤ ulp(hi)/2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DD {
    pub hi: f64,
    pub lo: f64,
}

fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl DD {
    pub const ZERO: DD = DD { hi: 0.0, lo: 0.0 };
    pub const ONE: DD = DD { hi: 1.0, lo: 0.0 };
    pub const PI: DD = DD {
        hi: std::f64::consts::PI,
        lo: 1.2246467991473532e-16,
    };
    pub const LN2: DD = DD {
        hi: std::f64::consts::LN_2,
        lo: 2.3190468138462996e-17,
    };
    pub fn new(x: f64) -> DD {
        DD { hi: x, lo: 0.0 }
    }
    /// The exact product of two f64 numbers.
    pub fn prod(a: f64, b: f64) -> DD {
        let (hi, lo) = two_prod(a, b);
        DD { hi, lo }
    }
    /// self + a·b with the exact product.
    pub fn add_prod(self, a: f64, b: f64) -> DD {
        self + DD::prod(a, b)
    }
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
    pub fn abs(self) -> DD {
        if self.hi < 0.0 { -self } else { self }
    }
    pub fn sqrt(self) -> DD {
        if self.hi <= 0.0 {
            return DD::ZERO;
        }
        let x = self.hi.sqrt();
        let (p, e) = two_prod(x, x);
        let r = ((self.hi - p) - e + self.lo) / (2.0 * x);
        let (hi, lo) = quick_two_sum(x, r);
        DD { hi, lo }
    }
    pub fn powi(self, n: u32) -> DD {
        let mut r = DD::ONE;
        for _ in 0..n {
            r = r * self;
        }
        r
    }
    /// Nearest integer (as f64).
    pub fn round(self) -> f64 {
        let r = self.hi.round();
        if r == self.hi {
            // hi is an integer: the low part decides ties.
            r + self.lo.round()
        } else {
            r
        }
    }
    /// e^x by argument reduction (k·ln2, then /2^10) and Taylor series.
    pub fn exp(self) -> DD {
        if self.hi < -700.0 {
            return DD::ZERO;
        }
        let k = (self.hi / std::f64::consts::LN_2).round();
        let r = self - DD::LN2 * DD::new(k);
        let r = r * DD::new(1.0 / 1024.0);
        let mut term = DD::ONE;
        let mut sum = DD::ONE;
        for i in 1..30 {
            term = term * r / DD::new(i as f64);
            sum = sum + term;
            if term.hi.abs() < 1e-36 {
                break;
            }
        }
        for _ in 0..10 {
            sum = sum * sum;
        }
        sum * DD::new(2f64.powi(k as i32))
    }
    /// e^x − 1, accurate for tiny x.
    pub fn expm1(self) -> DD {
        if self.hi.abs() > 0.5 {
            return self.exp() - DD::ONE;
        }
        let mut term = self;
        let mut sum = self;
        for i in 2..60 {
            term = term * self / DD::new(i as f64);
            sum = sum + term;
            if term.hi.abs() < 1e-36 * sum.hi.abs() {
                break;
            }
        }
        sum
    }
    /// (sin(πx), cos(πx)) for a DD argument.
    pub fn sincos_pi(self) -> (DD, DD) {
        // Reduce x modulo 2 into [−1, 1].
        let k = (self * DD::new(0.5)).round();
        let r = self - DD::new(2.0 * k);
        // Fold into [−1/2, 1/2] with cos sign flip.
        let (r, cs) = if r.hi > 0.5 {
            (DD::ONE - r, -1.0)
        } else if r.hi < -0.5 {
            (DD::new(-1.0) - r, -1.0)
        } else {
            (r, 1.0)
        };
        let y = DD::PI * r;
        let y2 = y * y;
        let mut s = y;
        let mut term = y;
        let mut c = DD::ONE;
        let mut cterm = DD::ONE;
        for i in 1..40 {
            let n = 2 * i;
            term = -(term * y2) / DD::new((n * (n + 1)) as f64);
            cterm = -(cterm * y2) / DD::new(((n - 1) * n) as f64);
            s = s + term;
            c = c + cterm;
            if term.hi.abs() < 1e-36 && cterm.hi.abs() < 1e-36 {
                break;
            }
        }
        (s, c * DD::new(cs))
    }
}

impl Add for DD {
    type Output = DD;
    fn add(self, b: DD) -> DD {
        let (s, e) = two_sum(self.hi, b.hi);
        let (t, f) = two_sum(self.lo, b.lo);
        let e = e + t;
        let (s, e) = quick_two_sum(s, e);
        let e = e + f;
        let (hi, lo) = quick_two_sum(s, e);
        DD { hi, lo }
    }
}
impl Neg for DD {
    type Output = DD;
    fn neg(self) -> DD {
        DD {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}
impl Sub for DD {
    type Output = DD;
    fn sub(self, b: DD) -> DD {
        self + (-b)
    }
}
impl Mul for DD {
    type Output = DD;
    fn mul(self, b: DD) -> DD {
        let (p, e) = two_prod(self.hi, b.hi);
        let e = e + (self.hi * b.lo + self.lo * b.hi);
        let (hi, lo) = quick_two_sum(p, e);
        DD { hi, lo }
    }
}
impl Div for DD {
    type Output = DD;
    fn div(self, b: DD) -> DD {
        let q1 = self.hi / b.hi;
        let r = self - b * DD::new(q1);
        let q2 = r.hi / b.hi;
        let r = r - b * DD::new(q2);
        let q3 = r.hi / b.hi;
        let (hi, lo) = quick_two_sum(q1, q2);
        DD { hi, lo } + DD::new(q3)
    }
}

/// A complex double-double.
#[derive(Debug, Clone, Copy)]
pub struct Cdd {
    pub re: DD,
    pub im: DD,
}

impl Cdd {
    pub fn mul(self, b: Cdd) -> Cdd {
        Cdd {
            re: self.re * b.re - self.im * b.im,
            im: self.re * b.im + self.im * b.re,
        }
    }
    /// self^n by binary powering.
    pub fn pow(self, mut n: u64) -> Cdd {
        let mut result = Cdd {
            re: DD::ONE,
            im: DD::ZERO,
        };
        let mut base = self;
        while n > 0 {
            if n & 1 == 1 {
                result = result.mul(base);
            }
            base = base.mul(base);
            n >>= 1;
        }
        result
    }
}

/// ∫_a^b f(x) dx by tanh-sinh quadrature; `f` receives (x, x − a, b − x) so
/// integrands can use the exact distances to the ends. Refines the step until
/// two levels agree to `rtol` relative to the result.
pub fn tanh_sinh(a: f64, b: f64, rtol: f64, f: impl Fn(f64, f64, f64) -> f64) -> f64 {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    let eval = |h: f64, odd_only: bool| -> f64 {
        let mut sum = 0.0;
        let kmax = (4.0 / h) as i64;
        for k in -kmax..=kmax {
            if odd_only && k % 2 == 0 {
                continue;
            }
            let t = k as f64 * h;
            let u = 0.5 * std::f64::consts::PI * t.sinh();
            let cosh_u = u.cosh();
            let w = 0.5 * std::f64::consts::PI * t.cosh() / (cosh_u * cosh_u);
            // Distances to the ends: b − x = 2·half/(1 + e^{2u}), x − a = 2·half/(1 + e^{−2u}).
            let db = 2.0 * half / (1.0 + (2.0 * u).exp());
            let da = 2.0 * half / (1.0 + (-2.0 * u).exp());
            if db <= 0.0 || da <= 0.0 || w == 0.0 {
                continue;
            }
            let x = if u > 0.0 { b - db } else { a + da };
            let _ = mid;
            sum += w * f(x, da, db);
        }
        sum
    };
    let mut h = 0.5;
    let mut s = eval(h, false);
    let mut est = s * h * half;
    for _ in 0..10 {
        h *= 0.5;
        s += eval(h, true);
        let next = s * h * half;
        if (next - est).abs() <= rtol * next.abs() {
            return next;
        }
        est = next;
    }
    est
}
