//! The tape's builder: shared subexpressions, folding and faults. The
//! simulator's plants and signals on the tape against the interpreter are
//! tested in the simulation stage (`sim/tape_agreement.rs`).

use super::*;

#[test]
fn shares_folds_and_faults() {
    // f(x, y) = [x * y + x * y; 2 * 3 + y; x / y; 0 * (x / y)]
    let mut b = Builder::new(2);
    let (x, y) = (b.input(0), b.input(1));
    let xy = b.bin(Binary::Mul, x, y);
    let xy2 = b.bin(Binary::Mul, x, y);
    assert_eq!(xy, xy2, "common subexpressions are shared");
    let s = b.bin(Binary::Add, xy, xy2);
    let (two, three) = (b.constant(2.0), b.constant(3.0));
    let six = b.bin(Binary::Mul, two, three);
    assert_eq!(b.value(six), Some(6.0), "constants fold");
    let c = b.bin(Binary::Add, six, y);
    let q = b.bin(Binary::DivChecked, x, y);
    let zero = b.constant(0.0);
    let dead = b.bin(Binary::Mul, zero, q);
    assert_eq!(b.value(dead), Some(0.0));
    let tape = b.finish(&[s, c, q, dead]).expect("a small tape"); // ok: unit test
    assert_eq!(tape.len(), 4, "x*y, the sum, 6 + y, x / y");
    let mut regs = tape.registers();
    tape.write(&mut regs, 0, &[3.0, 2.0]);
    tape.run(&mut regs).expect("no fault"); // ok: unit test
    let mut out = [0.0; 4];
    tape.read(&regs, &mut out);
    assert_eq!(out, [12.0, 8.0, 1.5, 0.0]);
    // The unused division still faults at y = 0, like the interpreter.
    tape.write(&mut regs, 0, &[3.0, 0.0]);
    assert_eq!(tape.run(&mut regs), Err(Fault));
}
