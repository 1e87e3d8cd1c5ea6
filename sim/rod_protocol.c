/* rod_protocol.c: the simulated trial (see rod_protocol.h for the definitions of the snap and
 * of the fast mode).
 *
 * Each step places the moving clamp at Delta W(t + dt) = rate (t + dt) / l and takes one
 * implicit Euler step (rod_dynamics.h), which also keeps the energy books (work of the clamp,
 * damping losses) reported in every sample so the energy balance can be checked. */
#include "rod_protocol.h"
#include "rod_dynamics.h"
#include "rod_observe.h"
#include "rod_quasi.h"
#include "rod_regime.h"
#include "rod_route.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Delta W at time t: constant rate, optionally reached by a smooth velocity ramp of length T. */
static double shear_at(double t, double rate, double T)
{
    if (T <= 0.0) return rate * t;
    if (t < T) return rate * (0.5 * t - T / (2.0 * M_PI) * sin(M_PI * t / T));
    return rate * (t - 0.5 * T);
}

/* Adaptive step control before the snap is detected (see the loop). */
#define ADAPT_CHANGE 2e-3        /* target change of Delta Z and of A per step */
#define ADAPT_CHANGE_MOVING 0.03 /* the same once Delta Z moves faster than the onset speed */
#define ADAPT_GROWTH 0.05        /* target relative growth of |A| per step */

/* A target above times the options' adapt_scale (0 counts as 1): the resolution ladder refines
 * these targets together with dt and the mesh (daemon/trial/predict_ladder.h). */
static double adapt_target(const rod_predict_opts *o, double base)
{
    return o->adapt_scale > 0.0 ? base * o->adapt_scale : base;
}

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

rod_predict_opts rod_predict_opts_default(void)
{
    rod_predict_opts o;
    memset(&o, 0, sizeof o);
    o.post_snap_time = 2.0;
    return o;
}

rod_predict_opts rod_predict_opts_fast(const rod_scene *sc)
{
    rod_predict_opts o = rod_predict_opts_default();
    o.adaptive = 1;
    o.quasi_static = 1;
    o.post_snap_dt_max = 5.0 * sc->dt;
    o.end_after_swing = 1;
    return o;
}

/* Where the shear phase stands between steps: time, Delta W, the step, the last observation,
 * and the snap watch (onset, detection, peak |A|, end of the first swing). */
typedef struct shear_state {
    double t, dw;
    double dt, dt_base, dt_max;
    double dz_prev, a_prev;
    double onset_dw, t_detect, peak;
    double slow;     /* Delta Z speed below which the snap has not begun (0.1 snap_speed) */
    int detected, swing_over;
    double snap_dir; /* sign of d(Delta Z)/dt when the snap was detected */
} shear_state;

/* The route to the upper state at the scene's Delta L; records Delta Z and the elastic energy
 * there. */
static rod_status predict_upper_state(rod_dyn *dyn, const rod_scene *sc, double *k1, rod_obs *ob,
                                      rod_prediction *out, char *why, size_t why_len)
{
    rod *r = dyn->r;
    rod_route_report rr = {0};
    rod_status st = rod_route_to_state(r, dyn->s, sc, +1, &rr);
    out->stage_route = 1;
    if (st != ROD_OK) {
        if (why)
            snprintf(why, why_len, "could not reach the upper state at Delta L = %g (%s, %.0f%% of the route done)",
                     sc->compression, rod_status_message(st), 100.0 * rr.reached);
        return st;
    }
    rod_observe(r, k1, ob);
    out->dz_upper = ob->dz;
    out->elastic_upper = rod_energy(r);
    if (!(ob->dz > 0.0)) {
        if (why) snprintf(why, why_len, "the route ended with Delta Z = %g, not in the upper state", ob->dz);
        return ROD_ERR_BRANCH_LOST;
    }
    return ROD_OK;
}

/* A warm start's state s (rod_predict_warm) re-solved for this strip at (dl, dw): one static,
 * minimising Newton solve from it; the state must be finite and on the upper branch. */
static rod_status predict_warm_solve(rod_dyn *dyn, const rod_scene *sc, const rod_snapshot *s, double dl, double dw,
                                     double *k1, rod_obs *ob)
{
    rod *r = dyn->r;
    if (!s || s->ndof != r->ndof || s->n != r->n) return ROD_ERR_SCENE;
    rod_snapshot_load(r, s);
    rod_set_folds(r, 1.0, 1.0);
    rod_set_clamps(r, dl, dw);
    rod_frames_update(r);
    rod_newton_opts no = rod_newton_opts_static(sc);
    no.positive_definite = 1;
    rod_newton_report nr;
    rod_status st = rod_newton_solve(r, dyn->s, &no, &nr);
    if (st != ROD_OK) return st;
    rod_observe(r, k1, ob);
    return ob->dz > 0.0 && isfinite(ob->dz) && isfinite(ob->a) ? ROD_OK : ROD_ERR_BRANCH_LOST;
}

/* The warm start's upper state, recorded as predict_upper_state records the route's. */
static rod_status predict_warm_upper(rod_dyn *dyn, const rod_scene *sc, const rod_predict_warm *w, double *k1,
                                     rod_obs *ob, rod_prediction *out)
{
    rod_status st = predict_warm_solve(dyn, sc, w->upper, sc->compression, 0.0, k1, ob);
    if (st != ROD_OK) return st;
    out->dz_upper = ob->dz;
    out->elastic_upper = rod_energy(dyn->r);
    return ROD_OK;
}

/* Fast mode's quasi-static start: follows the equilibrium in Delta W until the dynamics must take
 * over, and starts the shear phase there. */
static rod_status predict_quasi_start(rod_dyn *dyn, const rod_scene *sc, double dl, double rate,
                                      const rod_predict_warm *warm, double *k1, rod_obs *ob, shear_state *ss,
                                      rod_prediction *out, char *why, size_t why_len)
{
    rod_quasi_report qr;
    double dw0 = 0.0;
    if (warm) {
        /* From the nearby strip's static state at warm->dw, when it re-solves (else cold). */
        if (predict_warm_solve(dyn, sc, warm->at, dl, warm->dw, k1, ob) != ROD_OK) return ROD_ERR_BRANCH_LOST;
        dw0 = warm->dw;
        rod_dyn_start(dyn, dl, dw0);
    }
    rod_status st = rod_quasi_follow_from(dyn, sc, dl, dw0, rate, sc->shear_max, &qr);
    if (st != ROD_OK) {
        if (why) snprintf(why, why_len, "out of memory in the quasi-static start");
        return st;
    }
    /* The switch must lie more than the margin after the warm start, where the cold start's
       extrapolation and going back would have put it (rod_quasi.h). */
    if (warm && qr.steps <= qr.back + 2) return ROD_ERR_BRANCH_LOST;
    ss->dw = qr.dw_switch;
    ss->t = ss->dw / rate;
    out->quasi_solves = qr.solves;
    out->dw_switch = qr.dw_switch;
    rod_observe(dyn->r, k1, ob);
    return ROD_OK;
}

/* Whether the step just taken (of length h) must be redone shorter: after detection, a long step
 * in which Delta Z or A changed by more than 0.06; before it, a long step that overshot the step
 * control's targets (predict_next_dt) twice over. Sets the shorter step. */
static int predict_step_overshot(const rod_predict_opts *o, const rod_obs *ob, double h, shear_state *ss)
{
    if (o->adaptive && ss->detected && o->post_snap_dt_max > ss->dt_base) {
        /* After detection only the peak |A| is still measured: a step may be long while
         * Delta Z and A change by less than 0.06 in it. */
        if (h > ss->dt_base && fmax(fabs(ob->dz - ss->dz_prev), fabs(ob->a - ss->a_prev)) > 0.06) {
            ss->dt = fmax(0.5 * ss->dt, ss->dt_base);
            return 1;
        }
    } else if (o->adaptive && h > ss->dt_base) {
        /* A long step that overshot the step control's targets (below) twice over is
         * redone shorter. */
        double target =
            adapt_target(o, fabs(ob->dz - ss->dz_prev) / h >= ss->slow ? ADAPT_CHANGE_MOVING : ADAPT_CHANGE);
        if (fmax(fabs(ob->dz - ss->dz_prev), fabs(ob->a - ss->a_prev)) > 2.0 * target ||
            fabs(ob->a - ss->a_prev) > 2.0 * adapt_target(o, ADAPT_GROWTH) * fabs(ss->a_prev) + 1e-12) {
            ss->dt = fmax(0.25 * ss->dt, ss->dt_base);
            return 1;
        }
    }
    return 0;
}

/* The snap watch after an accepted step: the onset is the last Delta W where Delta Z moved slower
 * than ss->slow, the snap is detected when it moves faster than the scene's snap_speed, the peak
 * |A| is kept throughout, and the first swing ends where Delta Z turns round. */
static void predict_snap_watch(const rod_scene *sc, const rod_predict_opts *o, const rod_obs *ob,
                               double speed, shear_state *ss, rod_prediction *out)
{
    if (!ss->detected) {
        if (speed < ss->slow) {
            ss->onset_dw = ss->dw;
            ss->peak = fabs(ob->a);
        } else {
            ss->peak = fmax(ss->peak, fabs(ob->a));
        }
        if (speed > sc->snap_speed) {
            ss->detected = 1;
            ss->t_detect = ss->t;
            out->snapped = 1;
            out->snap_dw = ss->onset_dw;
            ss->snap_dir = ob->dz > ss->dz_prev ? 1.0 : -1.0;
        }
    } else {
        ss->peak = fmax(ss->peak, fabs(ob->a));
        /* The first swing ends where Delta Z turns round. */
        if (o->end_after_swing && (ob->dz - ss->dz_prev) * ss->snap_dir < 0.0) ss->swing_over = 1;
    }
}

/* The next step's length from how much the last one changed Delta Z and A. */
static void predict_next_dt(const rod_predict_opts *o, double change, double growth, double speed,
                            int iterations, shear_state *ss)
{
    if (o->adaptive && ss->detected && o->post_snap_dt_max > ss->dt_base) {
        if (change < 0.03) ss->dt = fmin(1.5 * ss->dt, o->post_snap_dt_max);
        else ss->dt = fmax(0.5 * ss->dt, ss->dt_base);
    } else if (o->adaptive && !ss->detected) {
        /* The next step aims at a change of ADAPT_CHANGE in Delta Z and in A, and at a
         * relative growth of |A| of ADAPT_GROWTH: near an instability the asymmetry grows
         * exponentially from the imperfection, and that growth sets the snap's delay. Once
         * Delta Z moves faster than the onset speed the onset is behind (as long as it does
         * not slow down again) and the steps need only find the detection, so the change
         * aimed at is ADAPT_CHANGE_MOVING. The step changes by a factor within [0.5, 1.5],
         * grows only while Newton needs at most 4 iterations, and stays within
         * [dt, 100 dt]. */
        double ratio = adapt_target(o, speed >= ss->slow ? ADAPT_CHANGE_MOVING : ADAPT_CHANGE) / fmax(change, 1e-300);
        ratio = fmin(ratio, adapt_target(o, ADAPT_GROWTH) / fmax(growth, 1e-300));
        ratio = fmin(fmax(ratio, 0.5), iterations <= 4 ? 1.5 : 1.0);
        ss->dt = fmin(fmax(ss->dt * ratio, ss->dt_base), ss->dt_max);
    } else if (o->adaptive) {
        ss->dt = fmax(0.5 * ss->dt, ss->dt_base);
    } else if (ss->dt < ss->dt_base) {
        ss->dt = fmin(2.0 * ss->dt, ss->dt_base);
    }
}

/* One run; with warm set, a warm start that does not hold sets *cold and returns (the caller
   runs again cold). */
static rod_status predict_run(const rod_scene *sc, const rod_predict_opts *o, const rod_predict_warm *warm,
                              rod_prediction *out, int *cold, char *why, size_t why_len)
{
    double t_start = wall_now();
    memset(out, 0, sizeof *out);
    rod_dyn dyn;
    rod_status st = rod_dyn_open(&dyn, sc, why, why_len);
    if (st != ROD_OK) return st;
    rod *r = dyn.r;
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    if (!k1) {
        st = ROD_ERR_ALLOC;
        if (why) snprintf(why, why_len, "out of memory allocating the simulator workspace");
        goto done;
    }

    rod_obs ob;
    double l = r->length, dl = sc->compression, rate = sc->shear_rate / l;
    if (warm && !(o->adaptive && o->quasi_static && o->ramp_time <= 0.0 && rate > 0.0)) warm = NULL;
    if (warm) {
        if (predict_warm_upper(&dyn, sc, warm, k1, &ob, out) != ROD_OK) {
            *cold = 1;
            goto done;
        }
        out->warm = 1;
    } else {
        st = predict_upper_state(&dyn, sc, k1, &ob, out, why, why_len);
        if (st != ROD_OK) goto done;
    }
    rod_dyn_start(&dyn, dl, 0.0);

    shear_state ss;
    memset(&ss, 0, sizeof ss);
    ss.dt_base = sc->dt;
    ss.dt = ss.dt_base;
    ss.dt_max = 100.0 * ss.dt_base;
    if (o->adaptive && o->quasi_static && o->ramp_time <= 0.0 && rate > 0.0) {
        st = predict_quasi_start(&dyn, sc, dl, rate, warm, k1, &ob, &ss, out, why, why_len);
        if (st == ROD_ERR_BRANCH_LOST && warm) {
            *cold = 1;
            st = ROD_OK;
            goto done;
        }
        if (st != ROD_OK) goto done;
    }
    ss.dz_prev = ob.dz;
    ss.a_prev = ob.a;
    ss.slow = 0.1 * sc->snap_speed;
    /* Counted in double and saturated: a huge count (post_snap_time = 1e300, or a scene that
     * skipped rod_scene_check) must not overflow the conversion to long (undefined behaviour). */
    double cap_steps = ceil(sc->shear_max / rate / ss.dt_base + o->post_snap_time / ss.dt_base) + 1000.0;
    long cap = cap_steps < 9.0e18 ? (long)cap_steps : LONG_MAX;
    out->stage_shear = 1;
    out->stage_damping = sc->damping > 0.0;

    for (;;) {
        if (!ss.detected && ss.dw >= sc->shear_max - 1e-12) break;
        if (ss.detected && (ss.t - ss.t_detect >= o->post_snap_time || ss.swing_over)) break;
        if (out->steps + out->rejected >= cap) {
            st = ROD_ERR_TIME_LIMIT;
            if (why) snprintf(why, why_len, "step cap of %ld reached at Delta W = %g", cap, ss.dw);
            goto done;
        }
        double h = ss.dt;
        double dw_new = shear_at(ss.t + h, rate, o->ramp_time);
        if (!ss.detected && dw_new > sc->shear_max) {
            /* Land exactly on the shear limit (the rate is constant once past the ramp). */
            h = fmax(1e-12, (sc->shear_max - ss.dw) / rate);
            dw_new = sc->shear_max;
        }
        rod_newton_report nr;
        rod_status ts = rod_dyn_try(&dyn, h, dl, dw_new, &nr);
        if (ts != ROD_OK) {
            out->rejected++;
            ss.dt *= 0.5;
            if (ss.dt < ss.dt_base / 1024.0) {
                st = ts;
                if (why)
                    snprintf(why, why_len, "time step failed at Delta W = %.6f even at dt = %g s: %s (residual %.3g)",
                             ss.dw, ss.dt, rod_status_message(ts), nr.residual_rel);
                goto done;
            }
            continue;
        }
        rod_observe(r, k1, &ob);
        if (predict_step_overshot(o, &ob, h, &ss)) {
            rod_dyn_reject(&dyn);
            out->rejected++;
            continue;
        }
        rod_dyn_accept(&dyn);
        ss.t += h;
        ss.dw = dw_new;
        out->steps++;
        if (!isfinite(ob.dz) || !isfinite(ob.a) || !isfinite(ob.a_cam)) {
            st = ROD_ERR_NAN;
            if (why) snprintf(why, why_len, "non-finite observation at Delta W = %g", ss.dw);
            goto done;
        }
        double speed = fabs(ob.dz - ss.dz_prev) / h;
        predict_snap_watch(sc, o, &ob, speed, &ss, out);
        if (o->on_sample) {
            rod_sample smp = {ss.t, ss.dw, ob.dz, ob.a, ob.a_cam, ob.dz_cam, 0, dyn.kinetic, dyn.work, dyn.damped};
            smp.elastic = rod_energy(r);
            if (o->on_sample(o->user, &smp, r)) break;
        }
        double change = fmax(fabs(ob.dz - ss.dz_prev), fabs(ob.a - ss.a_prev));
        double growth = fabs(ob.a - ss.a_prev) / (fabs(ss.a_prev) + 1e-12);
        ss.dz_prev = ob.dz;
        ss.a_prev = ob.a;
        predict_next_dt(o, change, growth, speed, nr.iterations, &ss);
    }
    out->peak_abs_a = ss.peak;
    out->asymmetric = out->snapped && rod_regime_asymmetric(ss.peak, sc->asym_threshold);
    out->dz_final = ob.dz;
    out->sim_time = ss.t;

done:
    out->count = r->count;
    out->wall_s = wall_now() - t_start;
    free(k1);
    rod_dyn_close(&dyn);
    return st;
}

rod_status rod_predict(const rod_scene *sc, const rod_predict_opts *o, rod_prediction *out,
                       char *why, size_t why_len)
{
    rod_predict_opts def = rod_predict_opts_default();
    if (!o) o = &def;
    int cold = 0;
    rod_status st = predict_run(sc, o, o->warm, out, &cold, why, why_len);
    if (cold) st = predict_run(sc, o, NULL, out, &cold, why, why_len);
    return st;
}
