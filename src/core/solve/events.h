/* The events of a run, in one place: the root functions the integrators watch (end stops and
 * the collapse guard), what happens at an end-stop impact, and the breakpoints of the scripted
 * inputs, where a run stops exactly. Every threshold is one named constant here. Private. */
#ifndef FLEX3RPR_EVENTS_H
#define FLEX3RPR_EVENTS_H

#include "flex3rpr/sim.h"
#include "residual.h"
#include "queries.h"

/* Root functions of state y, all crossing downwards: the end stops rho_i - min and max - rho_i
 * (rows 2i, 2i + 1; constant 1 without end stops) and the collapse guard
 * rho_i + l - F3R_COLLAPSE_LEG_FRACTION l (row F3R_COLLAPSE_ROOT + i), which stops a run before
 * the beam's root reaches A_i, where the loop closure and the constraint Jacobian degenerate. */
#define F3R_NROOTS 9
#define F3R_COLLAPSE_ROOT 6
#define F3R_COLLAPSE_LEG_FRACTION 0.1
/* Impacts repeat without end when a force holds a piston against its stop: past this many
 * impacts within 1 ms the legs stop dead (a plastic impact) and lock at the stop, as contact. */
#define F3R_MAX_IMPACTS_PER_MS 200
/* Below this rebound speed (m/s) a leg comes to rest on its stop (locks) instead of rebounding:
 * the rebounds that would follow shrink geometrically (a Zeno sequence) and grow shorter than one
 * integrator step, so root finding would miss one and let the piston pass the stop. */
#define F3R_RESTING_SPEED 0.01

/* A free leg's stop roots fire this far (m) past the stop, not on it: a leg that starts a segment
 * on its stop (put there by contacts.c) then has its root armed however it moves, and an event
 * puts it back (contacts.h F3R_STROKE_TOLERANCE bounds what a run accepts). */
#define F3R_STOP_ROOT_OFFSET 1e-10
/* A locked leg's force root fires where its stop pulls by this much (N), so that at the event the
 * stop clearly pulls and the leg is released. */
#define F3R_STOP_FORCE_ROOT_OFFSET 1e-8
/* A locked leg whose integrated stroke drifts this far (m) off its stop stops the integrator,
 * which puts it back on the stop (the Baumgarte term only pulls it back at its rate). */
#define F3R_LOCK_DRIFT 5e-10

/* g (F3R_NROOTS) at state y of the formulation. A leg locked at a stop (locked[i] -1 at min, +1
 * at max) watches its stop's force stop_force[i] instead: row 2i (min) or 2i + 1 (max) crosses
 * zero where the stop would have to pull, and the leg is released; its other row crosses zero
 * where it drifts F3R_LOCK_DRIFT off the stop. Returns 0, or 1 when y does not close (the
 * integrators take that as a recoverable failure). */
int f3r_event_roots(const f3r_model* m, f3r_formulation form, const double* y, const int* locked,
                    const double* stop_force, double* g);

/* The first breakpoint of the scripted inputs in (t, t_out]: 1 with *t_stop set, else 0. */
int f3r_event_next_breakpoint(const f3r_model* m, double t, double t_out, double* t_stop);

/* The leg (0..2) whose collapse guard fired according to root_info, or -1. */
int f3r_event_collapsed_leg(const int* root_info);

/* The error of a run stopped by the collapse guard of `leg` at t in state y. */
f3r_status f3r_event_collapse_error(const f3r_model* m, f3r_formulation form, const double* y,
                                    int leg, double t, f3r_error* err);

/* Impacts counted in the current window of 1 ms, for F3R_MAX_IMPACTS_PER_MS (contacts.h). */
typedef struct {
  double window_start;
  long count;
} f3r_impact_window;

#endif
