/*
 * Native "pin inside a bore" contact for the twin's clearance joints: collider, contact law,
 * regularized Coulomb friction.
 *
 * Collider. MuJoCo has no concave primitive, so a bushing (a hollow cylinder) cannot be a geom.
 * Its documented extension point is the global collision table mjCOLLISIONFUNC[type1][type2]
 * (MuJoCo docs, programming/simulation "Collision detection"). This module installs a function
 * for the cylinder-cylinder pair: when exactly one of the two geoms is marked as a bore (geom
 * user data field marker == BORE_MAGIC), the pair is treated as a pin of radius R_j inside a
 * bore of radius R_i (both taken from geom_size[0]) with parallel axes (the bore's z axis):
 *
 *   e    = pin centre - bore centre, projected on the plane normal to the bore axis
 *   dist = (R_i - R_j) - |e|            (> 0: gap; < 0: penetration delta = -dist)
 *   n    = e / |e|                       (from the bore centre towards the contact)
 *
 * One contact at the midpoint between the two surfaces along n, normal pointing from geom1 to
 * geom2 (MuJoCo's convention), first tangent = axis x normal (in the plane of motion). The
 * geometry is an exact circle: no faceting error, whatever the clearance. Every other
 * cylinder-cylinder pair is passed to the function that was in the table before (MuJoCo's
 * own), so unmarked models behave as usual. The collider is stateless and thread-safe.
 * Nothing assumes which bodies carry the two geoms: at the ground pivot A the bore sits on the
 * world body (body 0: zero velocity, no dofs, so mj_applyFT gives the friction's reaction
 * nothing to act on) and the pin's body (the crank) has two slides before its hinge; velocities
 * come from cvel (every dof of the body's chain), so the journal's slip on the frame is
 * omega x (contact point - journal centre) plus the journal's own motion.
 *
 * Contact law (user[BORE_LAW] > 0). The force of the contact's normal row is the reference
 * engine's law, not MuJoCo's solref/solimp spring: with delta the penetration, delta' its rate
 * (> 0 approaching), v_imp the approach speed stored when the contact event starts (floored at
 * user[BORE_SPEED_FLOOR], kept in d->userdata[user[BORE_SLOT]]; 0 = no event):
 *
 *   law 1, hysteresis (Lankarani-Nikravesh, Hunt-Crossley, Flores; S003 Eq. 17):
 *       F = K delta^n (1 + chi max(delta'/v_imp, -1)),  K = user[STIFFNESS], n = user[EXPONENT],
 *       chi = user[DAMPING];
 *   law 2, linear: F = K delta + c delta',  c = user[DAMPING];
 *   law 3, ADAMS IMPACT: F = K delta^n + STEP(delta, 0, 0, d_max, c_max) delta',  c_max =
 *       user[DAMPING], d_max = user[DMAX];
 *   law 4, Johnson's cylindrical law: as law 1 with K delta^n replaced by F_J(delta), the F
 *       that solves delta = (F/K) [ln(4 dR K/F) - 1] (Johnson, Contact Mechanics, 1985, 5.6;
 *       K = pi L E*, dR = user[DMAX] the radial clearance; twin/contact_params.py
 *       johnson_elastic_force, the same algorithm: F = -K delta / W_-1(-e delta/(4 dR)), and
 *       K delta beyond the relation's turning point delta = 4 dR/e^2).
 *
 * How the solver is made to apply it. For an active contact row MuJoCo's primal solvers
 * (Newton, CG) return the force f = D (aref - J qacc) = (aref - a)/R, a = J qacc the row's
 * constrained acceleration, R = efc_R = 1/efc_D its regularizer, and aref = -B efc_vel -
 * K I (efc_pos - efc_margin) its reference acceleration, with (K, B, I) = efc_KBIP (MuJoCo
 * docs, computation: "the force relation R f = aref - a"; engine_core_constraint.c,
 * mj_constraintUpdate: force = -D (J qacc - aref) while J qacc < aref, 0 otherwise). Rows, R and
 * KBIP are built in the position stage; mjcb_passive runs in the velocity stage before
 * mj_referenceConstraint computes aref from KBIP. Here, in mjcb_passive, the row gets
 *
 *   R = 1 / gamma,  gamma = theta c h,   B = R c,   K = R F_e / (I delta)
 *
 * (F_e = K delta^n, c = chi F_e / v_imp: the elastic part and the damping coefficient of the
 * law; h the timestep), so that aref = R (F_e + c delta') = R F(delta, delta') and
 *
 *   f = F(delta, delta') - gamma a = F_e + c [(1 - theta) delta' + theta delta'_end],
 *
 * because with MuJoCo's Euler update the row's end-of-step penetration rate is delta'_end =
 * delta' - h a. The elastic term is explicit (evaluated at the step's start: with the
 * semi-implicit Euler update of positions this is the reference engine's symplectic Euler,
 * which keeps the elastic energy of an impact), the damping is the theta-method: trapezoidal
 * (theta = 1/2, second order) while c h / m_hat <= 2, and theta = 1 - m_hat/(c h) beyond, the
 * smallest theta whose velocity decay is monotonic (m_hat = 1/efc_diagA, the row's mass
 * estimate), so the large damping of a resting contact (v_imp at its floor) needs no step limit.
 * Where gamma is smaller than MuJoCo's own 1/R (start of contact: c -> 0), R is kept and the
 * residual -a/R is 1e-4 of the row's inertial force (the pair's impedance 1e-4). In the clamped
 * branch (delta'/v_imp < -1) the force is K delta^n (1 - chi), without a rate term. A pulling
 * law force makes aref < 0 and the solver leaves the row inactive: f = max(F, 0), decided
 * implicitly. In equilibrium (a = 0, delta' = 0) f = K delta^n exactly. R is also written into
 * iefc_R/iefc_D (islands) and into the diagonal of efc_AR (dual solvers: PGS, noslip). With an
 * elliptic friction cone (condim 3) the friction rows keep MuJoCo's regularizer and the
 * regularized cone's coefficient mu = friction sqrt(R_t/R) follows the new R (as MuJoCo sets it);
 * while sliding, MuJoCo's soft cone then adds to the normal force (the reason for the native
 * friction). Pyramidal cones are left to solref/solimp.
 * Assumes one mjcb_passive call per step (mj_step, mj_forward: the Euler and implicit
 * integrators; RK4 calls it per stage, and its end-of-step rate is not delta' - h a).
 *
 * Rates. The row is linear in qvel with J fixed at the step's start, and positions advance in
 * joint coordinates, so the penetration's true acceleration is a + b with b the velocity-product
 * part (-dJ/dt qvel, bore_bias_acceleration: n . (a_pin - a_bore) at qacc = 0 plus
 * |e'_perp|^2/|e|, the pin sliding along the bore's curve and the bodies' rotations). Over a step
 * the penetration changes by h s, s = delta'_end + h b / 2 (the step's secant rate), while the
 * next step starts at delta' = delta'_end + h b: in sliding contact the rate at a step's start
 * exceeds s by h b / 2. That is O(h), but the damping of a resting contact is huge (c = chi F_e
 * / v_imp at the 1 mm/s floor: 1e4-1e5 N s/m), so c h b / 2 reached 10-20 % of the normal force
 * at h = 1e-5 s on the bench (b ~ 35-70 m/s^2). The law is therefore applied on the secant
 * rate: at the row's fixed point (every step starts at the same delta', so a = -b) the force
 * above is F_e + c s + c h b (1/2 - theta), so aref gets R c h (theta - 1/2) b (nothing at
 * theta = 1/2) and f = F_e + c s; the friction's normal force is the law at the step's state with the same
 * rate, F(delta, delta' - h b / 2) = aref/R - theta c h b, the normal force the solver applies
 * in sliding contact (before, the friction took F(delta, delta') and its mu f_N exceeded mu0
 * times the applied normal force by up to 20 %, the cause of the twin's +10 % peak AC6 in the
 * 0.5 mm scene of analysis/contact_table.py).
 *
 * Force (user[BORE_FORCE_PIN] >= 0, mujoco.contact_source = "force"). The same law and friction
 * without a contact row: the builder removes the pin/bore pair, and the passive callback computes,
 * from the geoms' poses, e (pin centre - bore centre in the bore's plane), delta = |e| - (R_i -
 * R_j), n = e/|e|, the contact point p (midpoint of the surfaces, as the collider's), delta' = n .
 * (v_pin(p) - v_bore(p)) and the tangential slip along t = axis x n at the step's state, and applies
 * F = law(delta, delta', v_imp) (law_terms, the row's law; v_imp kept in the same userdata slot) and
 * the friction mu(|v_t|) F (friction_coefficient) as equal and opposite forces at p on the two
 * bodies (mj_applyFT into qfrc_passive). The rate: MuJoCo's (and the reference's) semi-implicit
 * Euler advances positions with the updated velocity, so the velocities at the step's start are
 * those of the half step before it; the law takes delta'(t_k) = (3 v_k - v_(k-1)) / 2 (v_k the
 * normal velocity above, v_(k-1) the previous step's, kept in the userdata slot after v_imp's).
 * Measured on the single impacts of twin check contact: the plain v_k (the reference engine's
 * choice) makes the peak force 1-6 % too large and the contact 1-4 % too short at h = 1e-5 s,
 * (3 v_k - v_(k-1)) / 2 within 0.3 % and 0.1 %. The two-step rate is stable while c h < m_hat (the
 * pair's effective mass along n, from M's factorization); where the law's damping exceeds
 * m_hat / (2 h) (a resting contact at the impact-speed floor under a large load) c = m_hat / (2 h).
 * One passive call per step is assumed (not RK4).  Both are explicit at the step's start: with MuJoCo's
 * semi-implicit Euler update this is exactly the reference engine's symplectic Euler of the same
 * forces, with no collision, row, or solver cost. A position-stage user sensor of dimension 4 on the
 * bore (the builder's replacement of the contact sensor) gets [1, F, 0, 0] while delta > 0.
 *
 * Friction. The pair is a frictionless (condim 1) MuJoCo contact: MuJoCo's soft elliptic cone
 * adds mu * (would-be sticking force) to the normal force while sliding, which inflated the
 * normal force by a median 23 % and up to 27x on the bench (measured, see the builder's
 * docstring). Friction is applied instead as a passive force, exactly the reference's
 * regularized Coulomb law (S003 Eq. 19-20):
 *
 *   f_T = mu(v_r) f_N,  mu = 0 below v0, mu0 (v_r - v0)/(v1 - v0) between, mu0 above v1,
 *
 * opposing the tangential relative velocity v_r of the contact points on the pin and on the
 * bore (rotations included). f_N is the law's force at the step's state, F(delta, delta')
 * (aref/R of the row), as in the reference engine; for a solref/solimp row (law 0) it is the
 * soft constraint's prediction aref/(A_hat + R) (exactly k delta + c delta' for a flat, tiny
 * impedance). Fields BORE_MU0, BORE_V0, BORE_V1; with BORE_FRICTION = 1 the same fields hold the
 * Adams/COSMOS law of S001 (mu_d, v_s, v_d) and BORE_MUS its mu_s. A user sensor (mjcb_sensor, objtype geom = the
 * bore) reports the friction force on the pin along t = axis x n, n from the bore centre
 * towards the pin, summed over the bore's contacts. Declared needstage="pos" (the model's
 * file does), the value is written by the passive callback that computes the friction, in the
 * same forward pass: MuJoCo calls a position-stage user sensor before the velocity stage and
 * then leaves its slot alone, while a velocity-stage user sensor makes every step run
 * mj_subtreeVel first (0.1 us per step here, for nothing the friction needs) and would compute
 * the friction a second time. The position-stage callback marks the sensors' own slots in the
 * mjData (mark_sensors_pending), and only the passive callback of that same pass writes, so the
 * forward passes that skip sensors (RK4's intermediate stages) leave the step's value in place.
 * needstage="vel" still works the old way (the value computed by the sensor callback).
 *
 * One set of hooks for every model. MuJoCo's collision table and callbacks are process-wide
 * ("global and not model-specific", its API reference), so every hook here is a dispatcher that
 * reads all it needs from the model and data it is given: parameters from the geom/joint user data
 * and <numeric> elements, per-scene state from d->userdata, the sensor mark from d->sensordata.
 * Nothing is kept between calls; the only file-scope variables are the pointers below, written once
 * by install() (under the GIL) and the same for every model. check_model() names what a model lays
 * out wrongly, since a callback can only skip it.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include "_native.h"

#ifndef BORE_MODULE
#define BORE_MODULE _bore
#endif
#define BORE_STR2(x) #x
#define BORE_STR(x) BORE_STR2(x)
#define BORE_CAT2(a, b) a##b
#define BORE_CAT(a, b) BORE_CAT2(a, b)

/* Layout of a bore geom's user data (m->geom_user row, nuser_geom = BORE_NUSER): the one
 * definition is twin/names.py BORE_USERDATA_FIELDS (same names, same order). The module reports
 * its layout (userdata_fields()) and twin/native/collider.py refuses to install it if
 * the two differ. */
enum bore_user {
  BORE_MARKER = 0,       /* BORE_MAGIC marks the geom as a bore */
  BORE_MU0,              /* regularized Coulomb friction: mu0 [-] (0 = off) */
  BORE_V0,               /* v0 [m/s]: mu = 0 below */
  BORE_V1,               /* v1 [m/s]: mu = mu0 above */
  BORE_LAW,              /* contact law: 0 = MuJoCo's solref/solimp, 1 = hysteresis, 2 = linear, 3 = ADAMS IMPACT,
                            4 = Johnson cylindrical */
  BORE_STIFFNESS,        /* K [N/m^n] (linear law: [N/m]) */
  BORE_EXPONENT,         /* n [-] (linear law: 1) */
  BORE_DAMPING,          /* hysteresis: chi [-]; linear: c [N s/m] */
  BORE_SPEED_FLOOR,      /* floor of the stored impact speed [m/s] */
  BORE_SLOT,             /* d->userdata index that keeps v_imp (-1 = none) */
  BORE_FRICTION,         /* friction law: 0 = regularized Coulomb (mu0, v0, v1), 1 = Adams/COSMOS */
  BORE_MUS,              /* Adams/COSMOS: static coefficient mu_s [-] (mu_d = mu0, v_s = v0, v_d = v1) */
  BORE_DMAX,             /* ADAMS IMPACT law: penetration of full damping d_max [m]; Johnson law: radial clearance [m] */
  BORE_FORCE_PIN,        /* -1: the law acts on the collider's contact row; >= 0: geom id of the pin, the law and
                            the friction act as passive forces between pin and bore, no contact row ("Force") */
  BORE_NUSER             /* number of fields */
};
static const char* const bore_user_names[] = {
  "marker", "mu0", "v0", "v1", "law", "stiffness", "exponent", "damping", "speed_floor", "slot",
  "friction", "mus", "dmax", "force_pin"
};
_Static_assert(sizeof(bore_user_names) / sizeof(bore_user_names[0]) == BORE_NUSER,
               "bore_user_names must name every field of enum bore_user");

enum bore_law { LAW_SOFT = 0, LAW_HYSTERESIS = 1, LAW_LINEAR = 2, LAW_IMPACT = 3, LAW_CYLINDER = 4 };

/* Johnson's cylindrical elastic force [N] at penetration delta > 0 [m] for K = pi L E* [N/m] and
 * radial clearance dr [m]: F = -K delta / W_-1(z), z = -e delta / (4 dr), by Halley's iteration
 * (twin/contact_params.py johnson_elastic_force, same steps); K delta beyond z = -1/e */
static mjtNum johnson_force(mjtNum delta, mjtNum K, mjtNum dr) {
  const mjtNum E = 2.718281828459045;
  if (!(delta > 0)) return 0;
  const mjtNum z = -E * delta / (4 * dr);
  if (z <= -1 / E) return K * delta;
  const mjtNum p2 = 2 * (1 + E * z);
  mjtNum w;
  if (p2 < 0.25) {
    const mjtNum p = sqrt(p2);
    w = -1 - p - p2 / 3;
  } else {
    const mjtNum l1 = log(-z);
    w = l1 - log(-l1);
  }
  for (int i = 0; i < 30; i++) {
    const mjtNum ew = exp(w);
    const mjtNum f = w * ew - z;
    const mjtNum wp1 = w + 1;
    if (wp1 == 0) break;
    const mjtNum dw = f / (ew * wp1 - (w + 2) * f / (2 * wp1));
    w -= dw;
    if (w > -1) w = -1;
    if (fabs(dw) <= 1e-15 * fabs(w)) break;
  }
  return -K * delta / w;
}

/* Layout of a guide joint's user data (m->jnt_user row, nuser_jnt >= GUIDE_NUSER): the one
 * definition is twin/names.py GUIDE_USERDATA_FIELDS. A slide or hinge joint marked with
 * GUIDE_MAGIC gets the reference's regularized Coulomb friction as a passive force on its dof:
 * f = -F ramp(|v|) sign(v), ramp = 0 below v0, (|v| - v0)/(v1 - v0) between, 1 above v1 (the
 * reference engine's slider guide, twin/reference/model.py; S003 Eq. 20's regularization). */
#define GUIDE_MAGIC 7302.0
enum guide_user {
  GUIDE_MARKER = 0,      /* GUIDE_MAGIC marks the joint */
  GUIDE_FORCE,           /* friction force F [N] (hinge: [N m]) */
  GUIDE_V0,              /* v0 [m/s]: no friction below */
  GUIDE_V1,              /* v1 [m/s]: full friction above */
  GUIDE_NUSER
};
static const char* const guide_user_names[] = {"marker", "force", "v0", "v1"};
_Static_assert(sizeof(guide_user_names) / sizeof(guide_user_names[0]) == GUIDE_NUSER,
               "guide_user_names must name every field of enum guide_user");

/* the ball-in-socket collider of the spatial mechanism (_socket.c): a marked sphere is a socket */
int twin_socket_install(void* table_addr);
void twin_socket_tangent(const mjtNum vball[3], const mjtNum vsocket[3], const mjtNum n[3], mjtNum t[3]);

/* what the hooks chain to (the table's cylinder-cylinder collider, callbacks installed before) and
 * the MuJoCo functions they call: set by install(), the same for every model */
static mjfCollision g_previous = NULL;
static mjfGeneric g_prev_passive = NULL;
static mjfSensor g_prev_sensor = NULL;
static twin_applyFT_t g_applyFT = NULL;
static twin_solveM_t g_solveM = NULL;

static int is_bore(const mjModel* m, int g) {
  return m->nuser_geom >= BORE_NUSER && m->geom_user[g * m->nuser_geom + BORE_MARKER] == BORE_MAGIC;
}

/* e = pin centre - bore centre projected on the plane normal to the bore axis a (geom z, world);
 * returns |e| */
static mjtNum bore_eccentricity(const mjData* d, int gb, int gp, mjtNum e[3], mjtNum a[3]) {
  const mjtNum* xb = d->geom_xpos + 3 * gb;
  const mjtNum* xp = d->geom_xpos + 3 * gp;
  const mjtNum* R = d->geom_xmat + 9 * gb;
  a[0] = R[2];
  a[1] = R[5];
  a[2] = R[8];
  e[0] = xp[0] - xb[0];
  e[1] = xp[1] - xb[1];
  e[2] = xp[2] - xb[2];
  const mjtNum ea = e[0] * a[0] + e[1] * a[1] + e[2] * a[2];
  e[0] -= ea * a[0];
  e[1] -= ea * a[1];
  e[2] -= ea * a[2];
  return sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
}

static int collide_pin_bore(const mjModel* m, mjData* d, mjPreContact* con,
                            int g1, int g2, mjtNum margin) {
  int b1 = is_bore(m, g1), b2 = is_bore(m, g2);
  if (b1 == b2) {
    return g_previous ? g_previous(m, d, con, g1, g2, margin) : 0;
  }
  int gb = b1 ? g1 : g2, gp = b1 ? g2 : g1;
  const mjtNum* xp = d->geom_xpos + 3 * gp;
  const mjtNum* R = d->geom_xmat + 9 * gb;
  mjtNum e[3], a[3];
  const mjtNum ecc = bore_eccentricity(d, gb, gp, e, a);
  const mjtNum rb = m->geom_size[3 * gb], rp = m->geom_size[3 * gp];
  const mjtNum dist = (rb - rp) - ecc;
  if (dist > margin) return 0;
  mjtNum n[3];
  if (ecc > 1e-300) {
    n[0] = e[0] / ecc; n[1] = e[1] / ecc; n[2] = e[2] / ecc;
  } else {                                       /* centred: any radial direction */
    n[0] = R[0]; n[1] = R[3]; n[2] = R[6];
  }
  const mjtNum s = rp + 0.5 * dist;             /* pin centre -> midpoint of the surfaces */
  const mjtNum sg = b1 ? -1.0 : 1.0;            /* normal from geom1 to geom2 */
  con->dist = dist;
  con->pos[0] = xp[0] + s * n[0];
  con->pos[1] = xp[1] + s * n[1];
  con->pos[2] = xp[2] + s * n[2];
  con->normal[0] = sg * n[0];
  con->normal[1] = sg * n[1];
  con->normal[2] = sg * n[2];
  con->tangent[0] = a[1] * con->normal[2] - a[2] * con->normal[1];
  con->tangent[1] = a[2] * con->normal[0] - a[0] * con->normal[2];
  con->tangent[2] = a[0] * con->normal[1] - a[1] * con->normal[0];
  return 1;
}

/* velocity of the material point p of body b (world frame), from the com-based cvel */
static void point_velocity(const mjModel* m, const mjData* d, int b, const mjtNum p[3], mjtNum v[3]) {
  const mjtNum* cv = d->cvel + 6 * b;
  const mjtNum* c = d->subtree_com + 3 * m->body_rootid[b];
  const mjtNum r[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
  v[0] = cv[3] + cv[1] * r[2] - cv[2] * r[1];
  v[1] = cv[4] + cv[2] * r[0] - cv[0] * r[2];
  v[2] = cv[5] + cv[0] * r[1] - cv[1] * r[0];
}

/* velocities va, vb of the contact point on geom1's and geom2's bodies; returns the normal
 * relative velocity (> 0: separating), as the contact row's efc_vel */
static mjtNum contact_velocity(const mjModel* m, const mjData* d, const mjContact* con,
                               mjtNum va[3], mjtNum vb[3]) {
  point_velocity(m, d, m->geom_bodyid[con->geom[0]], con->pos, va);
  point_velocity(m, d, m->geom_bodyid[con->geom[1]], con->pos, vb);
  const mjtNum* n12 = con->frame;               /* from geom1 to geom2 */
  return n12[0] * (vb[0] - va[0]) + n12[1] * (vb[1] - va[1]) + n12[2] * (vb[2] - va[2]);
}

/* velocity-product acceleration of the material point p of body b (world frame): the point's
 * acceleration at qacc = 0 without gravity, i.e. the com-based sum of cdof_dot qvel over the
 * body's chain converted to a point as mj_objectAcceleration does (+ omega x v_p) */
static void point_bias_acceleration(const mjModel* m, const mjData* d, int b, const mjtNum p[3],
                                    mjtNum acc[3]) {
  mjtNum s[6] = {0, 0, 0, 0, 0, 0};
  for (int bb = b; bb > 0; bb = m->body_parentid[bb]) {
    const int adr = m->body_dofadr[bb], num = m->body_dofnum[bb];
    for (int j = adr; j < adr + num; j++) {
      const mjtNum* cd = d->cdof_dot + 6 * j;
      const mjtNum qd = d->qvel[j];
      for (int k = 0; k < 6; k++) s[k] += cd[k] * qd;
    }
  }
  const mjtNum* c = d->subtree_com + 3 * m->body_rootid[b];
  const mjtNum r[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
  const mjtNum* w = d->cvel + 6 * b;
  mjtNum v[3];
  point_velocity(m, d, b, p, v);
  acc[0] = s[3] + s[1] * r[2] - s[2] * r[1] + w[1] * v[2] - w[2] * v[1];
  acc[1] = s[4] + s[2] * r[0] - s[0] * r[2] + w[2] * v[0] - w[0] * v[2];
  acc[2] = s[5] + s[0] * r[1] - s[1] * r[0] + w[0] * v[1] - w[1] * v[0];
}

/* velocity-product part of the penetration's acceleration of a pin/bore contact (bore geom
 * gb): delta = |e| - (R_i - R_j), delta' = n . e', delta'' = n . e'' + |e'_perp|^2 / |e| (e the
 * pin centre minus the bore centre in the bore's plane, n = e/|e|); returns the part of delta''
 * that does not depend on qacc (the row's -dJ/dt qvel: MuJoCo's row acceleration J qacc omits it) */
static mjtNum bore_bias_acceleration(const mjModel* m, const mjData* d, const mjContact* con, int gb) {
  const int gp = con->geom[0] == gb ? con->geom[1] : con->geom[0];
  const int bp = m->geom_bodyid[gp], bb = m->geom_bodyid[gb];
  const mjtNum* xp = d->geom_xpos + 3 * gp;
  const mjtNum* xb = d->geom_xpos + 3 * gb;
  const mjtNum* R = d->geom_xmat + 9 * gb;
  const int sph = m->geom_type[gb] == mjGEOM_SPHERE;  /* a socket (_socket.c): no axis, e in 3D */
  const mjtNum a[3] = {sph ? 0 : R[2], sph ? 0 : R[5], sph ? 0 : R[8]};
  mjtNum e[3] = {xp[0] - xb[0], xp[1] - xb[1], xp[2] - xb[2]};
  const mjtNum ea = e[0] * a[0] + e[1] * a[1] + e[2] * a[2];
  for (int k = 0; k < 3; k++) e[k] -= ea * a[k];
  const mjtNum ecc = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  if (!(ecc > 1e-300)) return 0;
  const mjtNum n[3] = {e[0] / ecc, e[1] / ecc, e[2] / ecc};
  mjtNum vp[3], vb[3], ap[3], ab[3];
  point_velocity(m, d, bp, xp, vp);
  point_velocity(m, d, bb, xb, vb);
  point_bias_acceleration(m, d, bp, xp, ap);
  point_bias_acceleration(m, d, bb, xb, ab);
  mjtNum ed[3] = {vp[0] - vb[0], vp[1] - vb[1], vp[2] - vb[2]};
  const mjtNum eda = ed[0] * a[0] + ed[1] * a[1] + ed[2] * a[2];
  for (int k = 0; k < 3; k++) ed[k] -= eda * a[k];
  const mjtNum edn = ed[0] * n[0] + ed[1] * n[1] + ed[2] * n[2];
  const mjtNum perp2 = ed[0] * ed[0] + ed[1] * ed[1] + ed[2] * ed[2] - edn * edn;
  return n[0] * (ap[0] - ab[0]) + n[1] * (ap[1] - ab[1]) + n[2] * (ap[2] - ab[2]) + perp2 / ecc;
}

/* the bore geom of contact con (or -1 if it is not a pin/bore contact with a constraint row) */
static int contact_bore(const mjModel* m, const mjContact* con) {
  const int g1 = con->geom[0], g2 = con->geom[1];
  if (g1 < 0 || g2 < 0 || con->exclude || con->efc_address < 0) return -1;
  const int b1 = is_bore(m, g1), b2 = is_bore(m, g2);
  if (b1 == b2) return -1;
  return b1 ? g1 : g2;
}

/* whether the law is applied to this row (frictionless or elliptic contact rows) */
static int law_row(const mjModel* m, const mjData* d, int gb, int row) {
  const int law = (int)m->geom_user[gb * m->nuser_geom + BORE_LAW];
  const int type = d->efc_type[row];
  return (law == LAW_HYSTERESIS || law == LAW_LINEAR || law == LAW_IMPACT || law == LAW_CYLINDER) &&
         (type == mjCNSTR_CONTACT_FRICTIONLESS || type == mjCNSTR_CONTACT_ELLIPTIC);
}

/* replace the regularizer of efc row `row` by R (and D = 1/R) wherever the solver reads it */
static void set_regularizer(const mjModel* m, mjData* d, int row, mjtNum R) {
  const mjtNum dR = R - d->efc_R[row];
  d->efc_R[row] = R;
  d->efc_D[row] = 1 / R;
  if (d->nisland > 0 && d->map_efc2iefc) {          /* islands: the solver reads iefc_R/iefc_D */
    const int i = d->map_efc2iefc[row];
    if (i >= 0) {
      d->iefc_R[i] = R;
      d->iefc_D[i] = 1 / R;
    }
  }
  /* dual solvers read R from the diagonal of efc_AR = A + R (mj_projectConstraint) */
  if ((m->opt.solver == mjSOL_PGS || m->opt.noslip_iterations > 0) && d->efc_AR && d->nA > 0) {
    const int nefc = d->nefc;
    if (d->nA == nefc * nefc) {
      d->efc_AR[row * (nefc + 1)] += dR;
    } else if (d->efc_AR_rownnz && d->efc_AR_rowadr && d->efc_AR_colind) {
      const int adr = d->efc_AR_rowadr[row];
      for (int k = 0; k < d->efc_AR_rownnz[row]; k++) {
        if (d->efc_AR_colind[adr + k] == row) {
          d->efc_AR[adr + k] += dR;
          break;
        }
      }
    }
  }
}

/* the law's elastic force fe [N] and damping coefficient c [N s/m] at penetration delta > 0 [m],
 * rate delta' [m/s] (> 0 approaching) and stored impact speed vimp [m/s] (laws 1-4, module
 * docstring): the force is fe + c delta'. In the clamped branch of a hysteresis law (delta'/v_imp
 * < -1) fe = K delta^n (1 - chi) and c = 0. The one implementation of the law in this module: the
 * contact row (contact_law) and the passive force (force_bore) both call it. */
static void law_terms(const mjtNum* user, int law, mjtNum delta, mjtNum rate, mjtNum vimp, mjtNum* fe_out,
                      mjtNum* c_out) {
  const mjtNum K = user[BORE_STIFFNESS];
  mjtNum fe, c;
  if (law == LAW_HYSTERESIS || law == LAW_CYLINDER) {
    const mjtNum n = user[BORE_EXPONENT];
    const mjtNum chi = user[BORE_DAMPING];
    if (law == LAW_CYLINDER) fe = johnson_force(delta, K, user[BORE_DMAX]);
    else fe = K * twin_pow(delta, n);
    c = chi * fe / vimp;
    if (rate < -vimp) {                         /* clamp delta'/v_imp at -1: no rate term */
      fe *= 1 - chi;
      c = 0;
    }
  } else if (law == LAW_IMPACT) {             /* ADAMS IMPACT: K delta^n + STEP(delta; d_max) c_max delta' */
    const mjtNum n = user[BORE_EXPONENT];
    fe = K * twin_pow(delta, n);
    c = twin_step3(delta, 0, 0, user[BORE_DMAX], user[BORE_DAMPING]);
  } else {
    fe = K * delta;
    c = user[BORE_DAMPING];
  }
  *fe_out = fe;
  *c_out = c;
}

/* the friction law's coefficient at slip speed s = |v_t| >= 0 [m/s] (module docstring,
 * "Friction"): regularized Coulomb (mu0, v0, v1) or Adams/COSMOS (BORE_FRICTION = 1) */
static mjtNum friction_coefficient(const mjtNum* user, mjtNum s) {
  const mjtNum mu0 = user[BORE_MU0], v0 = user[BORE_V0], v1 = user[BORE_V1];
  mjtNum mu = 0;
  if (user[BORE_FRICTION] == 1) {
    /* Adams/COSMOS (S001 Table II): odd cubic STEP through 0 up to v_s = v0, STEP from mu_s to
     * mu_d = mu0 up to v_d = v1, mu_d above (twin.reference.contact.adams_mu) */
    const mjtNum mus = user[BORE_MUS];
    if (s < v0) mu = twin_step3(s, -v0, -mus, v0, mus);
    else mu = twin_step3(s, v0, mus, v1, mu0);
  } else {
    mu = twin_ramp_scaled(mu0, s, v0, v1);
  }
  return mu;
}

/* the theta-method weight of the law's damping on row `row` with c h = ch (module docstring): 1/2
 * while c h <= 2 m_hat, 1 - m_hat/(c h) beyond (m_hat = 1/efc_diagA, the row's mass estimate) */
static mjtNum row_theta(const mjData* d, int row, mjtNum ch) {
  const mjtNum mhat = d->efc_diagA[row] > 0 ? 1 / d->efc_diagA[row] : 0;
  return ch > 2 * mhat ? 1 - mhat / ch : 0.5;
}

/* the contact law (module docstring) on the normal row of each bore's contact; keeps v_imp */
static void contact_law(const mjModel* m, mjData* d) {
  const int nu = m->nuser_geom;
  if (nu < BORE_NUSER) return;
  for (int gb = 0; gb < m->ngeom; gb++) {
    const mjtNum* user = m->geom_user + gb * nu;
    if (user[BORE_MARKER] != BORE_MAGIC) continue;
    const int law = (int)user[BORE_LAW];
    if (law != LAW_HYSTERESIS && law != LAW_LINEAR && law != LAW_IMPACT && law != LAW_CYLINDER) continue;
    if (user[BORE_FORCE_PIN] >= 0) continue;     /* a passive force (force_bore), no row */
    const int slot = (int)user[BORE_SLOT];
    const int has_slot = slot >= 0 && slot < m->nuserdata;
    int icon = -1;
    for (int i = 0; i < d->ncon; i++) {
      if (contact_bore(m, d->contact + i) == gb) {
        icon = i;
        break;
      }
    }
    if (icon < 0) {                               /* no contact: the event is over */
      if (has_slot) d->userdata[slot] = 0;
      continue;
    }
    const mjContact* con = d->contact + icon;
    const int row = con->efc_address;
    if (!law_row(m, d, gb, row)) continue;
    mjtNum va[3], vb[3];
    const mjtNum rate = -contact_velocity(m, d, con, va, vb);  /* delta' (> 0 approaching) */
    mjtNum vimp = user[BORE_SPEED_FLOOR];
    if (has_slot) {
      if (!(d->userdata[slot] > 0)) d->userdata[slot] = fmax(rate, user[BORE_SPEED_FLOOR]);
      vimp = d->userdata[slot];
    }
    mjtNum* kbip = d->efc_KBIP + 4 * row;
    const mjtNum delta = -(d->efc_pos[row] - d->efc_margin[row]);
    if (!(delta > 0) || !(vimp > 0)) {            /* touching, not penetrating: no force */
      kbip[0] = 0;
      kbip[1] = 0;
      continue;
    }
    mjtNum fe, c;                                 /* elastic force, damping coefficient */
    law_terms(user, law, delta, rate, vimp, &fe, &c);
    const mjtNum ch = c * m->opt.timestep;
    const mjtNum theta = row_theta(d, row, ch);
    const mjtNum gamma = theta * ch;
    const mjtNum R0 = d->efc_R[row];
    const mjtNum R = gamma * R0 > 1 ? 1 / gamma : R0;
    if (R != R0) {
      set_regularizer(m, d, row, R);
      if (d->efc_type[row] == mjCNSTR_CONTACT_ELLIPTIC) {
        /* elliptic cone: the friction rows' regularizer and damping scale with the normal
         * row's (MuJoCo's regularized cone coefficient stays; their viscous force B v / R too) */
        for (int j = 1; j < con->dim; j++) {
          set_regularizer(m, d, row + j, d->efc_R[row + j] * (R / R0));
          d->efc_KBIP[4 * (row + j) + 1] *= R / R0;
        }
      }
    }
    const mjtNum imp = kbip[2] > 0 ? kbip[2] : 1;
    /* the damping on the penetration's change over the step (module docstring, "Rates") */
    const mjtNum chord = theta != 0.5 && c > 0 ? R * ch * (theta - 0.5) * bore_bias_acceleration(m, d, con, gb) : 0;
    kbip[0] = (R * fe + chord) / (imp * delta);
    kbip[1] = R * c;
  }
}

typedef struct {
  int pin_body, bore_body;
  mjtNum t[3];   /* in-plane tangent axis x n (n: bore centre -> pin) */
  mjtNum fn;     /* normal force of the law (or predicted by the soft constraint) [N] */
  mjtNum ft;     /* friction force on the pin along t [N] */
} friction_t;

/* friction of contact icon if it is an active pin/bore contact; returns 0 otherwise */
static int bore_friction(const mjModel* m, const mjData* d, int icon, friction_t* out) {
  const mjContact* con = d->contact + icon;
  const int gb = contact_bore(m, con);
  if (gb < 0) return 0;
  const int b1 = con->geom[0] == gb;
  const int gp = b1 ? con->geom[1] : con->geom[0];
  const mjtNum* user = m->geom_user + gb * m->nuser_geom;
  const int row = con->efc_address;
  const mjtNum* kbip = d->efc_KBIP + 4 * row;
  mjtNum va[3], vb[3];
  const mjtNum vel = contact_velocity(m, d, con, va, vb);
  const mjtNum* n12 = con->frame;               /* from geom1 to geom2 */
  /* the row's reference acceleration (mj_referenceConstraint's formula, own velocity) */
  const mjtNum aref = -kbip[1] * vel - kbip[0] * kbip[2] * (d->efc_pos[row] - d->efc_margin[row]);
  mjtNum fn;
  if (law_row(m, d, gb, row)) {
    /* the law's force at the step's state, its rate taken as the penetration's change over the
     * step (module docstring, "Rates"): aref/R - theta c h delta''_bias */
    fn = aref / d->efc_R[row];
    const mjtNum c = kbip[1] / d->efc_R[row];
    if (c > 0) {
      const mjtNum ch = c * m->opt.timestep;
      fn -= row_theta(d, row, ch) * ch * bore_bias_acceleration(m, d, con, gb);
    }
  } else {
    fn = aref / (d->efc_diagA[row] + d->efc_R[row]);
  }
  out->pin_body = m->geom_bodyid[gp];
  out->bore_body = m->geom_bodyid[gb];
  out->fn = fn > 0 ? fn : 0;
  const mjtNum sg = b1 ? -1.0 : 1.0;            /* n = sg * n12 points bore -> pin side */
  const mjtNum* R = d->geom_xmat + 9 * gb;
  const mjtNum a[3] = {R[2], R[5], R[8]};
  const mjtNum n[3] = {sg * n12[0], sg * n12[1], sg * n12[2]};
  out->t[0] = a[1] * n[2] - a[2] * n[1];
  out->t[1] = a[2] * n[0] - a[0] * n[2];
  out->t[2] = a[0] * n[1] - a[1] * n[0];
  const mjtNum* vpin = b1 ? vb : va;
  const mjtNum* vbore = b1 ? va : vb;
  if (m->geom_type[gb] == mjGEOM_SPHERE) twin_socket_tangent(vpin, vbore, n, out->t);  /* socket: along the slip */
  const mjtNum vt = (vpin[0] - vbore[0]) * out->t[0] + (vpin[1] - vbore[1]) * out->t[1] +
                    (vpin[2] - vbore[2]) * out->t[2];
  const mjtNum mu = friction_coefficient(user, fabs(vt));
  out->ft = twin_oppose(vt, mu * out->fn);
  return 1;
}

/* regularized Coulomb friction of the joints marked as guides (GUIDE_MAGIC) */
static void guide_friction(const mjModel* m, mjData* d) {
  const int nu = m->nuser_jnt;
  if (nu < GUIDE_NUSER) return;
  for (int j = 0; j < m->njnt; j++) {
    const mjtNum* user = m->jnt_user + j * nu;
    if (user[GUIDE_MARKER] != GUIDE_MAGIC) continue;
    if (m->jnt_type[j] != mjJNT_SLIDE && m->jnt_type[j] != mjJNT_HINGE) continue;
    const int dof = m->jnt_dofadr[j];
    const mjtNum v = d->qvel[dof];
    const mjtNum r = twin_ramp(fabs(v), user[GUIDE_V0], user[GUIDE_V1]);
    if (v > 0) d->qfrc_passive[dof] -= user[GUIDE_FORCE] * r;
    else if (v < 0) d->qfrc_passive[dof] += user[GUIDE_FORCE] * r;
  }
}

/* Position-stage sensors of the bores (friction, dimension 1; contact, dimension 4: "Force"): the
 * passive callback writes them, but only in a forward pass that computes sensors (RK4's
 * intermediate stages skip them and must leave the step's values). The sensor callback marks
 * such a pass in the data itself: at mjSTAGE_POS it writes PENDING (a NaN no computation makes)
 * into the first slot of each of these sensors, and the passive callback of the same pass finds
 * the mark, sets the slot back to MuJoCo's 0 and writes the values. Nothing outside the mjData:
 * any number of models and data, on any threads. */
static const uint64_t PENDING = 0x7ff8000000007301ULL;

static int bore_pos_sensor(const mjModel* m, int s) {
  return m->sensor_type[s] == mjSENS_USER && m->sensor_objtype[s] == mjOBJ_GEOM &&
         m->sensor_needstage[s] == mjSTAGE_POS && (m->sensor_dim[s] == 1 || m->sensor_dim[s] == 4) &&
         m->sensor_objid[s] >= 0 && is_bore(m, m->sensor_objid[s]);
}

static void mark_sensors_pending(const mjModel* m, mjData* d) {
  for (int s = 0; s < m->nsensor; s++) {
    if (bore_pos_sensor(m, s)) memcpy(d->sensordata + m->sensor_adr[s], &PENDING, sizeof PENDING);
  }
}

/* whether this pass computes the bores' position-stage sensors (the mark found and cleared) */
static int take_sensors_pending(const mjModel* m, mjData* d) {
  int pending = 0;
  for (int s = 0; s < m->nsensor; s++) {
    if (!bore_pos_sensor(m, s)) continue;
    mjtNum* slot = d->sensordata + m->sensor_adr[s];
    if (memcmp(slot, &PENDING, sizeof PENDING) == 0) {
      *slot = 0;
      pending = 1;
    }
  }
  return pending;
}

/* add ft to the position-stage friction sensors of bore geom gb */
static void add_friction_sensor(const mjModel* m, mjData* d, int gb, mjtNum ft) {
  for (int s = 0; s < m->nsensor; s++) {
    if (twin_user_sensor(m, s, mjOBJ_GEOM, gb, mjSTAGE_POS) && m->sensor_dim[s] == 1) d->sensordata[m->sensor_adr[s]] += ft;
  }
}

#include "_drivetrain.h"
#include "_guide.h"

static void passive_bore_joints(const mjModel* m, mjData* d);

static void passive_bore(const mjModel* m, mjData* d) {
  passive_bore_joints(m, d);
  guide_passive(m, d);       /* the guide clearance's contacts (before the drive train books them) */
  drivetrain_passive(m, d);  /* last: it books the other passive forces of the step */
}

/* the inverse effective mass of the pin/bore pair along n at p [1/kg]: w^T M^-1 w with w =
 * (J_pin(p) - J_bore(p))^T n (mj_applyFT builds w, mj_solveM uses the factorization of M that the
 * position stage made); 0 when the functions are missing or nv exceeds the local buffer */
enum { FORCE_NV_MAX = 64 };
static mjtNum inverse_mass(const mjModel* m, mjData* d, int bp, int bb, const mjtNum n[3], const mjtNum p[3]) {
  if (!g_applyFT || !g_solveM || m->nv > FORCE_NV_MAX) return 0;
  mjtNum w[FORCE_NV_MAX], x[FORCE_NV_MAX];
  for (int i = 0; i < m->nv; i++) w[i] = 0;
  const mjtNum nm[3] = {-n[0], -n[1], -n[2]};
  g_applyFT(m, d, n, NULL, p, bp, w);
  g_applyFT(m, d, nm, NULL, p, bb, w);
  g_solveM(m, d, x, w, 1);
  mjtNum a = 0;
  for (int i = 0; i < m->nv; i++) a += w[i] * x[i];
  return a;
}

/* contact_source = "force" (module docstring, "Force"): the law and the friction of bore gb as
 * passive forces between its pin (geom user[BORE_FORCE_PIN]) and the bore, no contact row */
static void force_bore(const mjModel* m, mjData* d, int gb, const mjtNum* user, int sensors) {
  const int gp = (int)user[BORE_FORCE_PIN];
  const int law = (int)user[BORE_LAW];
  const int slot = (int)user[BORE_SLOT];
  const int has_slot = slot >= 0 && slot < m->nuserdata;
  if (gp >= m->ngeom || !(law == LAW_HYSTERESIS || law == LAW_LINEAR || law == LAW_IMPACT || law == LAW_CYLINDER))
    return;
  const mjtNum* xp = d->geom_xpos + 3 * gp;
  /* a socket (a marked sphere, _socket.c): the ball's centre relative to the socket's in 3D, the
   * point at the ball's centre and the friction along the slip, as the socket collider's contact */
  const int socket = m->geom_type[gb] == mjGEOM_SPHERE;
  mjtNum e[3], a[3] = {0, 0, 0};
  mjtNum ecc;
  if (socket) {
    const mjtNum* xs = d->geom_xpos + 3 * gb;
    e[0] = xp[0] - xs[0]; e[1] = xp[1] - xs[1]; e[2] = xp[2] - xs[2];
    ecc = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  } else {
    ecc = bore_eccentricity(d, gb, gp, e, a);
  }
  const mjtNum delta = ecc - (m->geom_size[3 * gb] - m->geom_size[3 * gp]);
  if (!(ecc > 1e-300)) {                          /* centred: no direction, no contact */
    if (has_slot) d->userdata[slot] = 0;
    return;
  }
  const mjtNum n[3] = {e[0] / ecc, e[1] / ecc, e[2] / ecc};  /* bore centre -> pin */
  const mjtNum s = socket ? 0 : m->geom_size[3 * gp] - 0.5 * delta;  /* pin centre -> midpoint of the surfaces */
  const mjtNum p[3] = {xp[0] + s * n[0], xp[1] + s * n[1], xp[2] + s * n[2]};
  const int bp = m->geom_bodyid[gp], bb = m->geom_bodyid[gb];
  mjtNum vp[3], vb[3];
  point_velocity(m, d, bp, p, vp);
  point_velocity(m, d, bb, p, vb);
  const mjtNum dv[3] = {vp[0] - vb[0], vp[1] - vb[1], vp[2] - vb[2]};
  const mjtNum vk = n[0] * dv[0] + n[1] * dv[1] + n[2] * dv[2];  /* delta' of the velocities (> 0 approaching) */
  /* the rate at the step's time: velocities are those of the half step before (symplectic Euler),
   * so delta'(t_k) = (3 v_k - v_(k-1)) / 2, v_(k-1) kept in the slot after v_imp's */
  const int has_prev = has_slot && slot + 1 < m->nuserdata;
  const mjtNum rate = has_prev ? vk + 0.5 * (vk - d->userdata[slot + 1]) : vk;
  if (has_prev) d->userdata[slot + 1] = vk;
  if (!(delta > 0)) {                            /* no penetration: the event is over */
    if (has_slot) d->userdata[slot] = 0;
    return;
  }
  mjtNum vimp = user[BORE_SPEED_FLOOR];
  if (has_slot) {
    if (!(d->userdata[slot] > 0)) d->userdata[slot] = fmax(rate, user[BORE_SPEED_FLOOR]);
    vimp = d->userdata[slot];
  }
  if (!(vimp > 0)) return;
  mjtNum fe, c;
  law_terms(user, law, delta, rate, vimp, &fe, &c);
  if (c > 0) {
    /* explicit damping on the two-step rate is stable while c h < m_hat (the pair's effective
     * mass), its parasitic root -0.39 at c h = m_hat / 2: beyond that (a resting contact's
     * damping at the impact-speed floor under a large load) c = m_hat / (2 h) */
    const mjtNum h = m->opt.timestep;
    const mjtNum ainv = inverse_mass(m, d, bp, bb, n, p);
    if (ainv > 0 && c * h * ainv > 0.5) c = 0.5 / (h * ainv);
  }
  mjtNum fn = fe + c * rate;
  if (fn < 0) fn = 0;                            /* the law never pulls */
  mjtNum t[3] = {a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2], a[0] * n[1] - a[1] * n[0]};
  if (socket) twin_socket_tangent(vp, vb, n, t);  /* along the slip */
  const mjtNum vt = dv[0] * t[0] + dv[1] * t[1] + dv[2] * t[2];
  const mjtNum mu = friction_coefficient(user, fabs(vt));
  const mjtNum ft = twin_oppose(vt, mu * fn);   /* on the pin along t */
  if (sensors) {
    add_friction_sensor(m, d, gb, ft);
    for (int k = 0; k < m->nsensor; k++) {         /* the contact sensor: [found, normal force, 0, 0] */
      if (twin_user_sensor(m, k, mjOBJ_GEOM, gb, mjSTAGE_POS) && m->sensor_dim[k] == 4) {
        d->sensordata[m->sensor_adr[k]] = 1;
        d->sensordata[m->sensor_adr[k] + 1] = fn;
      }
    }
  }
  if (!g_applyFT || (fn == 0 && ft == 0)) return;
  const mjtNum F[3] = {-fn * n[0] + ft * t[0], -fn * n[1] + ft * t[1], -fn * n[2] + ft * t[2]};  /* on the pin */
  const mjtNum Fm[3] = {-F[0], -F[1], -F[2]};
  g_applyFT(m, d, F, NULL, p, bp, d->qfrc_passive);
  g_applyFT(m, d, Fm, NULL, p, bb, d->qfrc_passive);
}

static void passive_bore_joints(const mjModel* m, mjData* d) {
  if (g_prev_passive) g_prev_passive(m, d);
  const int sensors = take_sensors_pending(m, d);  /* this pass computes sensors */
  guide_friction(m, d);
  if (m->nuser_geom < BORE_NUSER) return;
  contact_law(m, d);
  for (int gb = 0; gb < m->ngeom; gb++) {
    const mjtNum* user = m->geom_user + gb * m->nuser_geom;
    if (user[BORE_MARKER] == BORE_MAGIC && user[BORE_FORCE_PIN] >= 0) force_bore(m, d, gb, user, sensors);
  }
  for (int i = 0; i < d->ncon; i++) {
    friction_t f;
    if (!bore_friction(m, d, i, &f)) continue;
    if (sensors) add_friction_sensor(m, d, contact_bore(m, d->contact + i), f.ft);
    if (f.ft == 0 || !g_applyFT) continue;
    const mjtNum F[3] = {f.ft * f.t[0], f.ft * f.t[1], f.ft * f.t[2]};
    const mjtNum Fm[3] = {-F[0], -F[1], -F[2]};
    g_applyFT(m, d, F, NULL, d->contact[i].pos, f.pin_body, d->qfrc_passive);
    g_applyFT(m, d, Fm, NULL, d->contact[i].pos, f.bore_body, d->qfrc_passive);
  }
}

static void sensor_friction(const mjModel* m, mjData* d, int stage) {
  if (g_prev_sensor) g_prev_sensor(m, d, stage);
  drivetrain_sensor(m, d, stage);
  if (m->nuser_geom < BORE_NUSER) return;
  if (stage == mjSTAGE_POS) {
    mark_sensors_pending(m, d);  /* the passive callback of this pass writes the values */
    return;
  }
  if (stage != mjSTAGE_VEL) return;
  for (int s = 0; s < m->nsensor; s++) {
    if (m->sensor_type[s] != mjSENS_USER || m->sensor_objtype[s] != mjOBJ_GEOM ||
        m->sensor_needstage[s] != mjSTAGE_VEL) continue;
    const int gb = m->sensor_objid[s];
    if (gb < 0 || !is_bore(m, gb)) continue;
    mjtNum value = 0;  /* summed over the bore's contacts */
    for (int i = 0; i < d->ncon; i++) {
      if (d->contact[i].geom[0] != gb && d->contact[i].geom[1] != gb) continue;
      friction_t f;
      if (bore_friction(m, d, i, &f)) value += f.ft;
    }
    d->sensordata[m->sensor_adr[s]] = value;
  }
}

/* install(table, passive_cb, sensor_cb, mj_applyFT) addresses -> True if installed now */
static PyObject* py_install(PyObject* self, PyObject* args) {
  (void)self;
  unsigned long long table_addr, passive_addr, sensor_addr, applyft_addr, solvem_addr = 0;
  if (!PyArg_ParseTuple(args, "KKKK|K", &table_addr, &passive_addr, &sensor_addr, &applyft_addr, &solvem_addr))
    return NULL;
  if (!table_addr || !passive_addr || !sensor_addr || !applyft_addr) {
    PyErr_SetString(PyExc_ValueError, "null address");
    return NULL;
  }
  mjfCollision (*table)[mjNGEOMTYPES] = (mjfCollision (*)[mjNGEOMTYPES])(uintptr_t)table_addr;
  mjfGeneric* passive = (mjfGeneric*)(uintptr_t)passive_addr;
  mjfSensor* sensor = (mjfSensor*)(uintptr_t)sensor_addr;
  int changed = 0;
  g_applyFT = (twin_applyFT_t)(uintptr_t)applyft_addr;
  if (solvem_addr) g_solveM = (twin_solveM_t)(uintptr_t)solvem_addr;
  /* (re)install each hook that is not ours, chaining what was there */
  if (table[mjGEOM_CYLINDER][mjGEOM_CYLINDER] != collide_pin_bore) {
    g_previous = table[mjGEOM_CYLINDER][mjGEOM_CYLINDER];
    table[mjGEOM_CYLINDER][mjGEOM_CYLINDER] = collide_pin_bore;
    changed = 1;
  }
  if (twin_socket_install((void*)table)) changed = 1;
  if (*passive != passive_bore) {
    g_prev_passive = *passive;
    *passive = passive_bore;
    changed = 1;
  }
  if (*sensor != sensor_friction) {
    g_prev_sensor = *sensor;
    *sensor = sensor_friction;
    changed = 1;
  }
  if (changed) Py_RETURN_TRUE;
  Py_RETURN_FALSE;
}

/* ------------------------------------------------------------------ model check */

/* the name of element adr in m->names ("" if unnamed) */
static const char* el_name(const mjModel* m, const int* name_adr, int id) {
  return m->names + name_adr[id];
}

/* Why the native code cannot run model m as laid out, in one line written to msg, or 0 if it can.
 * A callback cannot raise, and skips what it cannot read; twin refuses such a model before it runs
 * (twin.native.collider.check_model). Only what the model marks as native is checked. */
static int model_problem(const mjModel* m, char* msg, size_t n) {
  const int nu = m->nuser_geom;
  for (int g = 0; nu >= 1 && g < m->ngeom; g++) {
    const mjtNum* user = m->geom_user + g * nu;
    if (user[BORE_MARKER] != BORE_MAGIC) continue;
    const char* name = el_name(m, m->name_geomadr, g);
    if (nu < BORE_NUSER)
      return snprintf(msg, n, "geom '%s' is marked as a bore (user[0] = %g) but the model's geom user data have %d "
                      "fields, the native code reads %d (twin.names.BORE_USERDATA_FIELDS)", name, BORE_MAGIC, nu,
                      (int)BORE_NUSER);
    if (m->geom_type[g] != mjGEOM_CYLINDER && m->geom_type[g] != mjGEOM_SPHERE)
      return snprintf(msg, n, "geom '%s' is marked as a bore but is of type %d: a bore is a cylinder (pin in bore) "
                      "or a sphere (ball in socket)", name, m->geom_type[g]);
    const mjtNum law = user[BORE_LAW], fric = user[BORE_FRICTION];
    if (!(law == LAW_SOFT || law == LAW_HYSTERESIS || law == LAW_LINEAR || law == LAW_IMPACT || law == LAW_CYLINDER))
      return snprintf(msg, n, "geom '%s': user field 'law' is %g, allowed 0 to 4", name, law);
    if (!(fric == 0 || fric == 1))
      return snprintf(msg, n, "geom '%s': user field 'friction' is %g, allowed 0 or 1", name, fric);
    const mjtNum pin = user[BORE_FORCE_PIN], slot = user[BORE_SLOT];
    const int force = pin >= 0;
    if (!(pin == -1 || (pin >= 0 && pin < m->ngeom && pin == floor(pin) && pin != g)))
      return snprintf(msg, n, "geom '%s': user field 'force_pin' is %g, allowed -1 or another geom's id (0 to %d)",
                      name, pin, (int)m->ngeom - 1);
    const int need = force ? 2 : 1;  /* "Force": v_imp and the previous step's normal velocity */
    if (!(slot == -1 || (slot >= 0 && slot == floor(slot) && slot + need <= m->nuserdata)))
      return snprintf(msg, n, "geom '%s': user field 'slot' is %g, allowed -1 or a userdata index with %d slot(s) "
                      "from it (nuserdata = %d)", name, slot, need, (int)m->nuserdata);
  }
  const int nj = m->nuser_jnt;
  for (int j = 0; nj >= 1 && j < m->njnt; j++) {
    if (m->jnt_user[j * nj + GUIDE_MARKER] != GUIDE_MAGIC) continue;
    const char* name = el_name(m, m->name_jntadr, j);
    if (nj < GUIDE_NUSER)
      return snprintf(msg, n, "joint '%s' is marked as a guide (user[0] = %g) but the model's joint user data have "
                      "%d fields, the native code reads %d (twin.names.GUIDE_USERDATA_FIELDS)", name, GUIDE_MAGIC, nj,
                      (int)GUIDE_NUSER);
    if (m->jnt_type[j] != mjJNT_SLIDE && m->jnt_type[j] != mjJNT_HINGE)
      return snprintf(msg, n, "joint '%s' is marked as a guide but is neither a slide nor a hinge", name);
  }
  for (int i = 0; i < m->nnumeric; i++) {
    const mjtNum* p = m->numeric_data + m->numeric_adr[i];
    const int size = m->numeric_size[i];
    if (size < 1 || (p[0] != DT_MAGIC && p[0] != GC_MAGIC)) continue;
    const char* name = el_name(m, m->name_numericadr, i);
    const int dt = p[0] == DT_MAGIC;
    const int nfields = dt ? DT_NFIELDS : GC_NFIELDS;
    if (size < nfields)
      return snprintf(msg, n, "numeric '%s' is marked as the %s (data[0] = %g) but has %d values, the native code "
                      "reads %d (twin.names.%s)", name, dt ? "drive train" : "guide clearance", p[0], size, nfields,
                      dt ? "DRIVETRAIN_FIELDS" : "GUIDE_CLEARANCE_FIELDS");
    const int dofs[3] = {dt ? (int)p[DT_MOTOR_DOF] : (int)p[GC_DOF_X], dt ? (int)p[DT_CRANK_DOF] : (int)p[GC_DOF_Y],
                         dt ? (int)p[DT_CRANK_DOF] : (int)p[GC_DOF_R]};
    for (int k = 0; k < 3; k++) {
      if (dofs[k] < 0 || dofs[k] >= m->nv)
        return snprintf(msg, n, "numeric '%s': dof index %d outside 0 to %d", name, dofs[k], (int)m->nv - 1);
    }
    if (dt && ((int)p[DT_GUIDE_DOF] < -1 || (int)p[DT_GUIDE_DOF] >= m->nv))
      return snprintf(msg, n, "numeric '%s': field 'guide_dof' is %g, allowed -1 or 0 to %d", name, p[DT_GUIDE_DOF],
                      (int)m->nv - 1);
    if (dt && ((int)p[DT_ACT] < 0 || (int)p[DT_ACT] >= m->nu))
      return snprintf(msg, n, "numeric '%s': field 'actuator' is %g, allowed 0 to %d", name, p[DT_ACT], (int)m->nu - 1);
    if (dt && !(p[DT_STRIDE] >= 1))
      return snprintf(msg, n, "numeric '%s': field 'stride' is %g, allowed >= 1", name, p[DT_STRIDE]);
    const mjtNum base = dt ? p[DT_SLOT] : p[GC_SLOT];
    const int need = dt ? DT_NSTATE_FIXED + 2 * (int)m->nv : GC_NSTATE;
    if (!(base >= 0 && base == floor(base) && base + need <= m->nuserdata))
      return snprintf(msg, n, "numeric '%s': field 'slot' is %g, its state needs %d userdata slots from it "
                      "(nuserdata = %d)", name, base, need, (int)m->nuserdata);
  }
  return 0;
}

/* check_model(address of an mjModel) -> None, or the one-line reason the native code cannot run it */
static PyObject* py_check_model(PyObject* self, PyObject* arg) {
  (void)self;
  const unsigned long long addr = PyLong_AsUnsignedLongLong(arg);
  if (PyErr_Occurred()) return NULL;
  if (!addr) {
    PyErr_SetString(PyExc_ValueError, "null model address");
    return NULL;
  }
  char msg[512];
  if (model_problem((const mjModel*)(uintptr_t)addr, msg, sizeof msg) > 0) return PyUnicode_FromString(msg);
  Py_RETURN_NONE;
}

/* ------------------------------------------------------------------ layouts for twin/names.py */

static PyObject* names_tuple(const char* const* names, int n) {
  PyObject* out = PyTuple_New(n);
  if (!out) return NULL;
  for (int i = 0; i < n; i++) {
    PyObject* name = PyUnicode_FromString(names[i]);
    if (!name) {
      Py_DECREF(out);
      return NULL;
    }
    PyTuple_SET_ITEM(out, i, name);
  }
  return out;
}

static PyObject* py_header_version(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return PyLong_FromLong(mjVERSION_HEADER);
}

static PyObject* py_bore_magic(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return PyFloat_FromDouble(BORE_MAGIC);
}

static PyObject* py_userdata_fields(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return names_tuple(bore_user_names, BORE_NUSER);
}

static PyObject* py_guide_fields(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return names_tuple(guide_user_names, GUIDE_NUSER);
}

static PyObject* py_guide_magic(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return PyFloat_FromDouble(GUIDE_MAGIC);
}

static PyObject* py_drivetrain_fields(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return names_tuple(dt_field_names, DT_NFIELDS);
}

static PyObject* py_guide_clearance_fields(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return names_tuple(gc_field_names, GC_NFIELDS);
}

static PyObject* py_guide_clearance_layout(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return Py_BuildValue("(dii)", GC_MAGIC, (int)GC_NSTATE, (int)GC_NSENSOR);
}

static PyObject* py_drivetrain_layout(PyObject* self, PyObject* args) {
  (void)self, (void)args;
  return Py_BuildValue("(diii)", DT_MAGIC, (int)DT_NSTATE_FIXED, (int)DT_NSENSOR_TORQUE, (int)DT_NSENSOR);
}

static PyMethodDef methods[] = {
  {"install", py_install, METH_VARARGS, "install(table, passive, sensor, applyFT[, solveM]): addresses of mjCOLLISIONFUNC, mjcb_passive, mjcb_sensor and the functions mj_applyFT and mj_solveM."},
  {"check_model", py_check_model, METH_O, "check_model(address of an mjModel): None, or the one-line reason the native code cannot run the model as laid out."},
  {"header_version", py_header_version, METH_NOARGS, "mjVERSION_HEADER the module was compiled against."},
  {"bore_magic", py_bore_magic, METH_NOARGS, "geom user data marker value that marks a bore."},
  {"userdata_fields", py_userdata_fields, METH_NOARGS, "names of the bore geom's user data fields, in order (enum bore_user)."},
  {"guide_fields", py_guide_fields, METH_NOARGS, "names of a guide joint's user data fields, in order (enum guide_user)."},
  {"drivetrain_fields", py_drivetrain_fields, METH_NOARGS, "names of the drive train's numeric fields, in order (enum dt_field)."},
  {"drivetrain_layout", py_drivetrain_layout, METH_NOARGS, "(marker, fixed userdata slots before 2 nv, torque sensor dimension, accounts sensor dimension) of the drive train."},
  {"guide_clearance_fields", py_guide_clearance_fields, METH_NOARGS, "names of the guide clearance's numeric fields, in order (enum gc_field)."},
  {"guide_clearance_layout", py_guide_clearance_layout, METH_NOARGS, "(marker, userdata slots, sensor dimension) of the guide clearance."},
  {"guide_magic", py_guide_magic, METH_NOARGS, "joint user data marker value that marks a guide."},
  {NULL, NULL, 0, NULL}
};

static struct PyModuleDef module = {
  PyModuleDef_HEAD_INIT, BORE_STR(BORE_MODULE), NULL, -1, methods, NULL, NULL, NULL, NULL
};

PyMODINIT_FUNC BORE_CAT(PyInit_, BORE_MODULE)(void) { return PyModule_Create(&module); }
