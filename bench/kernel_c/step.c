/* A C yardstick for solver/kernel.py::advance on a uniform tool, summary only.

   The same scheme, contact solve, energy audit and extremes as the Numba kernel (its slot layouts
   for the ends, the extremes and the energy), for a uniform tool with no external force. Written
   for speed: the tool rows are eliminated once; a step is a vectorised pass for the right-hand
   sides, the Q sweep toward the struck end and the forward substitution (one multiply-add a node
   on the critical path of each, split like the kernel's into SEGMENTS independent chains with
   their carries; no recurrence at all for the explicit scheme), the scalar contact solve, and one
   vectorised pass that sums the energies and finds the stress extremes.

   Built by bench/kernel.py: gcc -O3 -march=native -shared -fPIC. Not used by the product. */

#include <math.h>

#define LANES 8
#define SEGMENTS 4    /* the kernel's segment_layout() */
#define MIN_SEGMENT 8

/* prm[] layout, filled by bench/kernel.py */
enum {
    P_H, P_TAU, P_R, P_E, P_RHO, P_AREA, P_WEIGHT_NEW, P_WEIGHT_OLD, P_CENTERED,
    P_END_MASSES, P_M1, P_W1, P_C1, P_ALPHA, P_C0, P_B1, P_C2, P_B2
};

/* End, extreme and energy slots: the kernel's (those it uses) */
enum {
    S_IN_CONTACT, S_CONTACT_START, S_FORCE_BEFORE, S_FORCE_BEFORE_THAT, S_FORCE_EARLIER,
    S_MEDIUM_FORCE, S_MEDIUM_FORCE_BEFORE, S_MEDIUM_FORCE_EARLIER, S_POTENTIAL_BEFORE,
    S_POTENTIAL_BEFORE_THAT
};
enum {
    X_PEAK_FORCE, X_PEAK_FORCE_TIME, X_MAX_COMPRESSION, X_MAX_COMPRESSION_X,
    X_MAX_COMPRESSION_TIME, X_MAX_TENSION, X_MAX_TENSION_X, X_MAX_TENSION_TIME, X_CONTACTS,
    X_CO_IMPACT, X_REBOUND_VELOCITY, X_ENERGY_EXCESS, X_FAILED_TIME, X_MIN_CONTACT_STEPS
};
enum {
    E_EXTERNAL_WORK, E_DISSIPATED_CONTACT, E_DISSIPATED_MEDIUM, E_STRIKER_KINETIC,
    E_TOOL_KINETIC, E_TOOL_STRAIN, E_CONTACT_POTENTIAL, E_MEDIUM_POTENTIAL
};

typedef struct { double c1, alpha, c0; } Law;

/* The spring force Φ'(d) and the potential Φ(d), with one power for both */
static inline double spring(double d, const Law *k, double *potential)
{
    if (d < 0.0) {
        *potential = 0.5 * k->c0 * d * d;
        return k->c0 * d;
    }
    const double force = k->c1 * pow(d, k->alpha + 1.0);
    *potential = force * d / (k->alpha + 2.0);
    return force;
}

static inline double stiffness(double d, const Law *k)
{
    if (d < 0.0) return k->c0;
    return k->alpha == 0.0 ? k->c1 : (k->alpha + 1.0) * k->c1 * pow(d, k->alpha);
}

/* (Φ(d) − Φ_ref)/(d − ref) and its derivative; midpoint values when d ≈ ref */
static inline void quotient(double d, double ref, double ref_pot, const Law *k,
                            double *f, double *df)
{
    double diff = d - ref;
    double pot;
    if (fabs(diff) > 1e-7 * (fabs(d) + fabs(ref))) {
        const double force = spring(d, k, &pot), inverse = 1.0 / diff;
        *f = (pot - ref_pot) * inverse;
        *df = (force - *f) * inverse;
    } else {
        double mid = 0.5 * (d + ref);
        *f = spring(mid, k, &pot);
        *df = 0.5 * stiffness(mid, k);
    }
}

/* δ + compliance·(quotient(δ) + damper·(δ − ref)) = free: Newton kept inside the bracket */
static double solve_overlap(double free, double compliance, double ref, double ref_pot,
                            double guess, const Law *k, double damper)
{
    double f, df;
    quotient(free, ref, ref_pot, k, &f, &df);
    double other = free - compliance * (f + damper * (free - ref));
    double lo = fmin(free, other), hi = fmax(free, other);
    if (lo == hi) return free;
    double x = fmin(fmax(guess, lo), hi);
    double scale = 1e-15 * (fabs(lo) + fabs(hi));
    for (int it = 0; it < 100; it++) {
        quotient(x, ref, ref_pot, k, &f, &df);
        double g = x + compliance * (f + damper * (x - ref)) - free;
        if (g == 0.0) return x;
        if (g > 0.0) hi = x; else lo = x;
        double x_new = x - g / (1.0 + compliance * (df + damper));
        if (!(lo < x_new && x_new < hi)) x_new = 0.5 * (lo + hi);
        if (fabs(x_new - x) <= scale || hi - lo <= scale) return x_new;
        x = x_new;
    }
    return x;
}

/* Where in the last step the overlap crossed zero, on the parabola through its last three values */
static double crossing(double before_that, double before, double now)
{
    double linear = before / (before - now);
    if (isnan(before_that)) return linear;
    double a = 0.5 * (now + before_that) - before, b = 0.5 * (now - before_that);
    double disc = b * b - 4.0 * a * before;
    if (a == 0.0 || disc < 0.0) return linear;
    double root = sqrt(disc);
    double x = (-b + root) / (2.0 * a);
    if (0.0 <= x && x <= 1.0) return x;
    x = (-b - root) / (2.0 * a);
    if (0.0 <= x && x <= 1.0) return x;
    return linear;
}

/* A stress extreme `value` of the layer un[] (s0 at the struck end): the running maximum (the
   kernel's, not refined between nodes). Where it is, the first node of that stress from the struck
   end, is searched only for a new record: most layers set none. */
static void record_stress(double *ext, int slot, double sign, double value, const double *un,
                          long n, double half_e_over_h, double s0, double h, double t)
{
    double peak = sign * value;
    if (peak > ext[slot]) {
        long node = n;
        if (value == s0)
            node = 0;
        else
            for (long i = 1; i < n; i++)
                if (half_e_over_h * (un[i + 1] - un[i - 1]) == value) {
                    node = i;
                    break;
                }
        ext[slot] = peak;
        ext[slot + 1] = node * h;
        ext[slot + 2] = t;
    }
}

/* Layers 0 … steps of the case in prm[] on n cells. u: 3·(n+1) (layer m in row m % 3), y: 3,
   work: 5·(n+1) (zeros), ends/ext/en: the kernel's ends (zeros), extremes (from new_extremes()) and
   energy (zeros), contacts: max_contacts × 2. Returns 0, or 1 on a non-finite value. */
int run(long n, long steps, const double *prm, double *u, double *y, double *work,
        double *ends, double *ext, double *en, double *contacts, long max_contacts)
{
    const double h = prm[P_H], tau = prm[P_TAU], r = prm[P_R], area = prm[P_AREA];
    const double wn = prm[P_WEIGHT_NEW], wo = prm[P_WEIGHT_OLD], wc = 1.0 - wn - wo;
    const int centered = prm[P_CENTERED] != 0.0, end_masses = prm[P_END_MASSES] != 0.0;
    const double m1 = prm[P_M1], w1 = prm[P_W1], b1 = prm[P_B1], c2 = prm[P_C2], b2 = prm[P_B2];
    const Law law = {prm[P_C1], prm[P_ALPHA], prm[P_C0]};
    const long stride = n + 1;
    double *p = work, *g = work + stride, *cp = work + 2 * stride, *pp = work + 3 * stride;
    double *d = work + 4 * stride; /* the explicit rows' increments, from rest */

    /* boundary_weights() */
    const double ew = end_masses ? wn : 1.0;
    const double sw = centered ? 0.5 : 1.0, df = centered ? 0.5 / tau : 1.0 / tau;
    const long back = centered ? 2 : 1;

    const double inv_tau2 = 1.0 / (tau * tau), m1_tau2 = m1 * inv_tau2;
    const double end_area = end_masses ? 0.5 * area : 0.0; /* node_area at both ends */
    const double mass_end = prm[P_RHO] * h * end_area * inv_tau2;
    const double k_end = area * prm[P_E] / h, e_over_h = prm[P_E] / h;
    const double half_e_over_h = 0.5 * e_over_h;
    const double strain_sigma = centered ? wn : 0.25;
    const double strain_cross = 1.0 - 2.0 * strain_sigma;
    const double kinetic_factor = 0.5 * prm[P_RHO] * h * inv_tau2;
    const double initial_energy = 0.5 * m1 * w1 * w1;
    const double wr = wn * r;

    /* factor_tool_rows(), Q_i = g_i·rhs_i + P_i·Q_{i+1}: on a uniform tool the coefficient of
       Q_{i+1} equals P_i (and nothing is carried into row n) */
    const double diag_n = mass_end + ew * k_end + sw * c2 + b2 * df;
    p[n] = ew * k_end / diag_n;
    g[n] = 1.0 / diag_n;
    for (long i = n - 1; i >= 1; i--) {
        g[i] = 1.0 / (1.0 + 2.0 * wr - wr * p[i + 1]);
        p[i] = wr * g[i];
    }
    const double a_0 = mass_end + ew * k_end * (1.0 - p[1]);
    /* segment_layout(): nodes 1 … head serially, then SEGMENTS segments of len nodes; each
       segment's multiples of its carries, Π coefficient over i … end and Π P over start … i */
    const long len = n >= SEGMENTS * MIN_SEGMENT ? n / SEGMENTS : 0, head = n - SEGMENTS * len;
    for (long start = head + 1; len > 0 && start <= n; start += len) {
        const long end = start + len - 1;
        double product = 1.0;
        for (long i = end; i >= start; i--) {
            product *= i == n ? 0.0 : p[i];
            cp[i] = product;
        }
        product = 1.0;
        for (long i = start; i <= end; i++) {
            product *= p[i];
            pp[i] = product;
        }
    }

    /* Layer 0 and layer −1 (row 2) */
    for (long i = 0; i < stride; i++) u[i] = u[2 * stride + i] = 0.0;
    y[0] = 0.0;
    y[2] = -w1 * tau;
    ends[S_IN_CONTACT] = 1.0;
    ends[S_CONTACT_START] = 0.0;
    ends[S_POTENTIAL_BEFORE] = ends[S_POTENTIAL_BEFORE_THAT] = 0.0;  /* Φ(0); before impact */

    for (long m = 1; m <= steps; m++) {
        /* rows of layers m, m − 1, m − 2 and the reference layer (C's % keeps the sign) */
        const long now = m % 3, cur = (m + 2) % 3, old = (m + 1) % 3, ref = (m + 3 - back) % 3;
        double *un = u + now * stride;
        const double *uc = u + cur * stride, *uo = u + old * stride, *ur = u + ref * stride;
        const double t = m * tau;
        const double y_cur = y[cur], y_old = y[old];
        const double delta_cur = y_cur - uc[0], delta_old = y_old - uo[0];
        const double delta_ref = y[ref] - ur[0];

        /* Right-hand sides over their diagonals (vectorised), then the Q sweep toward the struck
           end; Q_i is kept in un[i] until the substitution */
        double rhs = mass_end * (2.0 * uc[n] - uo[n]) - c2 * (1.0 - sw) * ur[n] + b2 * df * ur[n];
        if (end_masses) rhs -= k_end * ((wc * uc[n] + wo * uo[n]) - (wc * uc[n - 1] + wo * uo[n - 1]));
        un[n] = rhs * g[n];
        double q1 = 0.0, carry[SEGMENTS] = {0.0};
        if (wn != 0.0) {
            for (long i = 1; i < n; i++) {
                const double v_left = wc * uc[i - 1] + wo * uo[i - 1];
                const double v_mid = wc * uc[i] + wo * uo[i];
                const double v_right = wc * uc[i + 1] + wo * uo[i + 1];
                un[i] = (2.0 * uc[i] - uo[i] + r * (v_left - 2.0 * v_mid + v_right)) * g[i];
            }
            if (len > 0) {
                double *q0 = un + head + 1, *q1s = q0 + len, *q2 = q1s + len, *q3 = q2 + len;
                const double *c0 = p + head + 1, *c1 = c0 + len, *c2s = c1 + len, *c3 = c2s + len;
                double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
                for (long j = len - 1; j >= 0; j--) {
                    s0 = fma(c0[j], s0, q0[j]);  /* four independent chains */
                    q0[j] = s0;
                    s1 = fma(c1[j], s1, q1s[j]);
                    q1s[j] = s1;
                    s2 = fma(c2s[j], s2, q2[j]);
                    q2[j] = s2;
                    s3 = fma(c3[j], s3, q3[j]);  /* from 0: row n carries nothing */
                    q3[j] = s3;
                }
                for (int k = SEGMENTS - 1; k >= 1; k--) {
                    const long start = head + 1 + k * len;
                    carry[k - 1] = un[start] + cp[start] * carry[k];
                }
                q1 = un[head + 1] + cp[head + 1] * carry[0];
            }
            for (long i = head; i >= 1; i--) {
                q1 = fma(p[i], q1, un[i]);
                un[i] = q1;
            }
        } else {  /* explicit (σ = 0, v = u^n): uncoupled rows, no recurrence; in the kernel's
                     summed form, each node's increment d = u^m − u^{m−1} kept apart */
            for (long i = n - 1; i >= 1; i--) {
                d[i] += r * (uc[i - 1] - 2.0 * uc[i] + uc[i + 1]);
                un[i] = uc[i] + d[i];
            }
            q1 = un[1];
        }
        const double v_1 = wc * uc[1] + wo * uo[1], v_0 = wc * uc[0] + wo * uo[0];

        /* Striker row and struck-end row: one scalar equation in the new overlap */
        const double b_y = m1_tau2 * (2.0 * y_cur - y_old);
        double b_0 = mass_end * (2.0 * uc[0] - uo[0]) + ew * k_end * q1;
        if (end_masses) b_0 += k_end * (v_1 - v_0);
        /* Φ of the reference layer, as computed when it was new (0 before impact) */
        const double ref_pot = ends[back == 1 ? S_POTENTIAL_BEFORE : S_POTENTIAL_BEFORE_THAT];
        double delta = solve_overlap(b_y / m1_tau2 - b_0 / a_0, 1.0 / m1_tau2 + 1.0 / a_0,
                                     delta_ref, ref_pot, 2.0 * delta_cur - delta_old, &law,
                                     b1 * df);
        double f, dfd;
        quotient(delta, delta_ref, ref_pot, &law, &f, &dfd);
        const double force = f + b1 * df * (delta - delta_ref);
        const double y_new = (b_y - force) / m1_tau2, u0 = (b_0 + force) / a_0;
        if (!(fabs(y_new) < 1e300 && fabs(u0) < 1e300)) {
            ext[X_FAILED_TIME] = t;
            return 1;
        }
        y[now] = y_new;
        un[0] = u0;
        delta = y_new - u0;
        const double delta_rate = m == 1
            ? (delta - delta_cur) / tau
            : (3.0 * delta - 4.0 * delta_cur + delta_old) / (2.0 * tau);
        double pot;
        const double contact_force = spring(delta, &law, &pot) + b1 * delta_rate;
        const double s0 = -contact_force / area;

        /* Forward substitution: one multiply-add a node on the critical path; none when the
           interior rows are uncoupled, but at a massless working end */
        if (wn != 0.0) {
            double ui = u0;
            for (long i = 1; i <= head; i++) {
                ui = fma(p[i], ui, un[i]);
                un[i] = ui;
            }
            if (len > 0) {
                double *x0 = un + head + 1, *x1 = x0 + len, *x2 = x1 + len, *x3 = x2 + len;
                const double *p0 = p + head + 1, *p1 = p0 + len, *p2 = p1 + len, *p3 = p2 + len;
                const double *g0 = cp + head + 1, *g1 = g0 + len, *g2 = g1 + len, *g3 = g2 + len;
                double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
                for (long j = 0; j < len; j++) {  /* the true Q made on the way */
                    s0 = fma(p0[j], s0, fma(g0[j], carry[0], x0[j]));
                    x0[j] = s0;
                    s1 = fma(p1[j], s1, fma(g1[j], carry[1], x1[j]));
                    x1[j] = s1;
                    s2 = fma(p2[j], s2, fma(g2[j], carry[2], x2[j]));
                    x2[j] = s2;
                    s3 = fma(p3[j], s3, fma(g3[j], carry[3], x3[j]));
                    x3[j] = s3;
                }
                double before = ui;
                for (int k = 0; k < SEGMENTS; k++) {
                    double *x = un + head + 1 + k * len;
                    const double *pk = pp + head + 1 + k * len;
                    const double after = fma(pk[len - 1], before, x[len - 1]);
                    for (long j = 0; j < len; j++)
                        x[j] = fma(pk[j], before, x[j]);
                    before = after;
                }
            }
        } else {
            un[n] = fma(p[n], un[n - 1], un[n]);
        }

        /* One pass for the tool's energy and its interior stresses (node i − 1), in LANES
           independent partial sums and extremes so that it vectorises */
        double kin_l[LANES] = {0}, str_l[LANES] = {0}, low_l[LANES], high_l[LANES];
        for (int j = 0; j < LANES; j++)
            low_l[j] = high_l[j] = s0;
        double kinetic = 0.0, strain = 0.0;
        {
            double ea = un[1] - u0, eb = uc[1] - uc[0], du = un[1] - uc[1];
            kinetic += du * du;
            strain += strain_sigma * (ea * ea + eb * eb) + strain_cross * ea * eb;
        }
        long i = 2;
        for (; i + LANES <= n + 1; i += LANES) {
            for (int j = 0; j < LANES; j++) {
                long k = i + j;
                double ea = un[k] - un[k - 1], eb = uc[k] - uc[k - 1], du = un[k] - uc[k];
                kin_l[j] += du * du;
                str_l[j] += strain_sigma * (ea * ea + eb * eb) + strain_cross * ea * eb;
                double s = half_e_over_h * (un[k] - un[k - 2]);
                low_l[j] = s < low_l[j] ? s : low_l[j];
                high_l[j] = s > high_l[j] ? s : high_l[j];
            }
        }
        double s_low = s0, s_high = s0;
        for (int j = 0; j < LANES; j++) {
            kinetic += kin_l[j];
            strain += str_l[j];
            s_low = low_l[j] < s_low ? low_l[j] : s_low;
            s_high = high_l[j] > s_high ? high_l[j] : s_high;
        }
        for (; i <= n; i++) {
            double ea = un[i] - un[i - 1], eb = uc[i] - uc[i - 1], du = un[i] - uc[i];
            kinetic += du * du;
            strain += strain_sigma * (ea * ea + eb * eb) + strain_cross * ea * eb;
            double s = half_e_over_h * (un[i] - un[i - 2]);
            s_low = s < s_low ? s : s_low;
            s_high = s > s_high ? s : s_high;
        }
        /* kinetic holds nodes 1 … n at the interior area: put the ends at theirs */
        const double du_n = un[n] - uc[n], du_0 = u0 - uc[0];
        const double tool_kinetic = kinetic_factor * (area * kinetic
                                                      + (end_area - area) * du_n * du_n
                                                      + end_area * du_0 * du_0);
        const double tool_strain = 0.5 * e_over_h * area * strain;

        const double end_rate = m == 1 ? (un[n] - uc[n]) / tau
                                       : (3.0 * un[n] - 4.0 * uc[n] + uo[n]) / (2.0 * tau);
        const double velocity = m == 1 ? w1 : (3.0 * y_new - 4.0 * y_cur + y_old) / (2.0 * tau);
        const double medium_force = c2 * un[n] + b2 * end_rate;
        const double sn = -medium_force / area;
        s_low = sn < s_low ? sn : s_low;
        s_high = sn > s_high ? sn : s_high;

        /* Energy at layer m − ½ */
        const double dy = y_new - y_cur;
        const double striker_kinetic = 0.5 * m1 * dy * dy * inv_tau2;
        const double contact_pot = sw * pot + (1.0 - sw) * ends[S_POTENTIAL_BEFORE];
        const double medium_pot = 0.5 * c2 * (sw * un[n] * un[n] + (1.0 - sw) * uc[n] * uc[n]);
        double rate = df * (delta - delta_ref);
        en[E_DISSIPATED_CONTACT] += b1 * rate * rate * tau;
        rate = df * (un[n] - ur[n]);
        en[E_DISSIPATED_MEDIUM] += b2 * rate * rate * tau;
        en[E_STRIKER_KINETIC] = striker_kinetic;
        en[E_TOOL_KINETIC] = tool_kinetic;
        en[E_TOOL_STRAIN] = tool_strain;
        en[E_CONTACT_POTENTIAL] = contact_pot;
        en[E_MEDIUM_POTENTIAL] = medium_pot;
        const double balance = striker_kinetic + tool_kinetic + tool_strain + contact_pot
                               + medium_pot + en[E_DISSIPATED_CONTACT] + en[E_DISSIPATED_MEDIUM]
                               - initial_energy - en[E_EXTERNAL_WORK];
        if (!(fabs(balance) < 1e300)) {
            ext[X_FAILED_TIME] = t;
            return 1;
        }
        if (balance > ext[X_ENERGY_EXCESS]) ext[X_ENERGY_EXCESS] = balance;

        /* Stress extremes, peak force, contact intervals */
        record_stress(ext, X_MAX_COMPRESSION, -1.0, s_low, un, n, half_e_over_h, s0, h, t);
        record_stress(ext, X_MAX_TENSION, 1.0, s_high, un, n, half_e_over_h, s0, h, t);
        if (contact_force > ext[X_PEAK_FORCE]) {
            ext[X_PEAK_FORCE] = contact_force;
            ext[X_PEAK_FORCE_TIME] = t;
        }
        const double f1 = ends[S_FORCE_BEFORE], f2 = ends[S_FORCE_BEFORE_THAT];
        if (m >= 3 && f1 >= f2 && f1 > contact_force) {
            double curvature = 2.0 * f1 - f2 - contact_force;
            double offset = 0.5 * (contact_force - f2) / curvature;
            double vertex = f1 + 0.25 * (contact_force - f2) * offset;
            if (vertex > ext[X_PEAK_FORCE]) {
                ext[X_PEAK_FORCE] = vertex;
                ext[X_PEAK_FORCE_TIME] = t - tau + offset * tau;
            }
        }
        ends[S_FORCE_BEFORE_THAT] = f1;
        ends[S_FORCE_BEFORE] = contact_force;
        ends[S_POTENTIAL_BEFORE_THAT] = ends[S_POTENTIAL_BEFORE];
        ends[S_POTENTIAL_BEFORE] = pot;

        const int in_contact = ends[S_IN_CONTACT] != 0.0;
        if (in_contact && delta < 0.0) {
            double t_cross = t - tau + tau * crossing(m >= 2 ? delta_old : NAN, delta_cur, delta);
            long k = (long)ext[X_CONTACTS];
            if (k < max_contacts) {
                contacts[2 * k] = ends[S_CONTACT_START];
                contacts[2 * k + 1] = t_cross;
            }
            ext[X_CONTACTS] = k + 1;
            double steps_in = (t_cross - ends[S_CONTACT_START]) / tau;
            if (steps_in < ext[X_MIN_CONTACT_STEPS]) ext[X_MIN_CONTACT_STEPS] = steps_in;
            if (k == 0) {
                ext[X_CO_IMPACT] = t_cross;
                ext[X_REBOUND_VELOCITY] = velocity;
            }
            ends[S_IN_CONTACT] = 0.0;
        } else if (!in_contact && delta >= 0.0) {
            ends[S_IN_CONTACT] = 1.0;
            ends[S_CONTACT_START] = t - tau + tau * crossing(m >= 2 ? delta_old : NAN, delta_cur,
                                                            delta);
        }
    }
    return 0;
}
