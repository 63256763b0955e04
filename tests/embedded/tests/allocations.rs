//! The control step allocates nothing once warmed up: a counting global allocator around
#![allow(clippy::unwrap_used, clippy::expect_used)]
//! `InvariantController::step` and `IbvsController::step` (a 100 Hz loop must not touch the
//! heap).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use vsinv::core::se3::exp_twist;
use vsinv_embedded::{DT, cameras, controllers, object, start_pose, view};

struct Counting;

thread_local! {
    // Per thread, so that tests running in parallel do not count each other's allocations.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count_one() {
    ALLOCATIONS.with(|c| c.set(c.get() + 1));
}

// SAFETY: forwards to the system allocator, counting the calls that hand out memory.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_one();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Heap allocations made by `f`.
fn allocations_in(f: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.with(Cell::get);
    f();
    ALLOCATIONS.with(Cell::get) - before
}

#[test]
fn control_steps_allocate_nothing_after_warm_up() {
    let (_, k, _) = cameras().expect("cameras");
    let (mut invariant, mut ibvs, z_star) = controllers().expect("controllers");
    let object = object();
    let (mut pixels, mut depths) = (vec![[0.0; 2]; object.len()], vec![0.0; object.len()]);
    let visible = vec![true; object.len()];
    let mut pose = start_pose();
    // Warm-up: the first steps size the controllers' buffers.
    for _ in 0..3 {
        view(&object, &pose, &k, &mut pixels, &mut depths).expect("view");
        invariant.step(&pixels, &z_star).expect("step");
        ibvs.step(&pixels, &depths).expect("step");
    }
    let mut counted = [0usize; 3];
    for _ in 0..200 {
        view(&object, &pose, &k, &mut pixels, &mut depths).expect("view");
        let mut twist = Default::default();
        counted[0] += allocations_in(|| twist = invariant.step(&pixels, &z_star).expect("step"));
        counted[1] += allocations_in(|| {
            ibvs.step(&pixels, &depths).expect("step");
        });
        counted[2] += allocations_in(|| {
            invariant.step_visible(&pixels, &z_star, &visible).expect("step");
        });
        pose *= exp_twist(&(twist * DT).into()).expect("motion");
    }
    assert_eq!(counted, [0, 0, 0], "allocations in 200 steps: invariant, IBVS, invariant with visibility");
    // The counter does count: a Vec allocates.
    assert!(allocations_in(|| drop(std::hint::black_box(vec![1u8; 64]))) >= 1);
    // The steps drove the camera: it is closer to the goal (the identity) than it started.
    assert!(pose.translation.vector.norm() < start_pose().translation.vector.norm());
}

#[test]
fn servo_steps_allocate_nothing_while_running() {
    let (_, k, _) = cameras().expect("cameras");
    let mut servo = vsinv_embedded::servo().expect("servo");
    let object = object();
    let (mut pixels, mut depths) = (vec![[0.0; 2]; object.len()], vec![0.0; object.len()]);
    let mut pose = start_pose();
    // Warm-up: the noise meter's 32 images and the stop window fill their buffers.
    let mut allocations = 0;
    for i in 0..300 {
        view(&object, &pose, &k, &mut pixels, &mut depths).expect("view");
        let mut step = None;
        let counted = allocations_in(|| step = Some(servo.step(&pixels, None, None).expect("step")));
        let step = step.expect("a step");
        assert!(step.verdict.is_running(), "{:?}", step.verdict);
        if i >= 40 {
            allocations += counted;
        }
        pose *= exp_twist(&(step.twist * DT).into()).expect("motion");
    }
    assert_eq!(allocations, 0, "allocations in 260 running servo steps");
    assert!(pose.translation.vector.norm() < start_pose().translation.vector.norm());
}

#[test]
fn servo_loop_stops_converged_on_the_core_alone() {
    let (status, iterations, t, r) = vsinv_embedded::run_servo_loop().expect("loop");
    assert_eq!(status, vsinv::servo::Status::Converged, "{iterations} iterations, {t} m, {r} rad");
    assert!(t < 1e-3 && r.to_degrees() < 0.1, "{iterations} iterations, {t} m, {r} rad");
}

#[test]
fn loop_converges_on_the_core_alone() {
    let (iterations, t, r) = vsinv_embedded::run_invariant_loop(5000).expect("loop");
    assert!(t < 1e-3 && r.to_degrees() < 0.1, "{iterations} iterations, {t} m, {r} rad");
}
