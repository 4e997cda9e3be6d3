/*
 * The slider guide's two-sided clearance in the MuJoCo twin (joints.clearance_guide_mm > 0),
 * included by _bore.c and called from its passive callback.
 *
 * The slider body carries three joints at its reference point Cs on the guide line: the guide
 * slide along x, a transverse slide along y and a tilt hinge about z (dofs p[GC_DOF_X/Y/R]).
 * Its front and rear contact points are Cs + R(phi) (+-a, 0), between an upper rail at y = +c
 * and a lower one at y = -c (the rails are the world). Each point touches at most one rail:
 * penetration delta = p_y - c (upper; force -f_N y on the slider) or -c - p_y (lower; +f_N y),
 * delta' its rate. The normal force is the reference engine's hysteresis law (twin/reference/
 * guide.py): F = K delta^n (1 + chi max(delta'/v_imp, -1)), at least 0, v_imp the approach speed
 * stored at the start of the contact event (floored at p[GC_VMIN]) in d->userdata; friction on
 * the point's sliding speed p_x' (regularized Coulomb, S003 Eq. 19-20, or the Adams/COSMOS law).
 * The forces go straight into qfrc_passive as generalized forces of the three dofs (F_x, F_y and
 * (p - Cs) x F about the hinge): an explicit force like the reference engine's (no solver row),
 * so both engines evaluate the same law at the step's start. The event state is idempotent under
 * repeated calls at one state (mj_forward), and reset with d->userdata per scene.
 *
 * Parameters: the <numeric> whose first value is GC_MAGIC (fields enum gc_field, names
 * gc_field_names = twin.names.GUIDE_CLEARANCE_FIELDS). Outputs: a position-stage user sensor on
 * the tilt hinge of dimension GC_NSENSOR, written here (normal force along +y at the front and
 * rear points, friction along +x at each).
 */

#include "_native.h"

#define GC_MAGIC 7311.0

enum gc_field {
  GC_MARKER = 0, GC_DOF_X, GC_DOF_Y, GC_DOF_R, GC_SLOT, GC_C, GC_A, GC_K, GC_N, GC_CHI, GC_VMIN,
  GC_FRIC, GC_MU0, GC_V0, GC_V1, GC_MUS, GC_VS, GC_VD, GC_NFIELDS
};
static const char* const gc_field_names[] = {
  "marker", "dof_x", "dof_y", "dof_r", "slot", "c", "a", "k", "n", "chi", "v_min",
  "friction_law", "mu0", "v0", "v1", "mu_static", "v_static", "v_kinetic"
};
_Static_assert(sizeof(gc_field_names) / sizeof(gc_field_names[0]) == GC_NFIELDS,
               "gc_field_names must name every field of enum gc_field");
#define GC_NSTATE 4   /* [in, v_imp] of the front point, then the rear */
#define GC_NSENSOR 4

static const mjtNum* gc_params(const mjModel* m) {
  return twin_numeric(m, GC_MAGIC, GC_NFIELDS);
}

/* friction force along +x opposing the sliding speed v (the reference's friction_force /
 * adams_friction_force) */
static mjtNum gc_friction(const mjtNum* p, mjtNum v, mjtNum fn) {
  const mjtNum s = fabs(v);
  mjtNum mu;
  if (p[GC_FRIC] > 0.5) {
    mu = s < p[GC_VS] ? twin_step3(s, -p[GC_VS], -p[GC_MUS], p[GC_VS], p[GC_MUS])
                      : twin_step3(s, p[GC_VS], p[GC_MUS], p[GC_VD], p[GC_MU0]);
  } else {
    mu = p[GC_MU0] * twin_ramp(s, p[GC_V0], p[GC_V1]);
  }
  return twin_oppose(v, mu * fn);
}

static void guide_passive(const mjModel* m, mjData* d) {
  const mjtNum* p = gc_params(m);
  if (!p) return;
  const int base = (int)p[GC_SLOT];
  if (base < 0 || base + GC_NSTATE > m->nuserdata) return;
  mjtNum* st = d->userdata + base;
  const int dx = (int)p[GC_DOF_X], dy = (int)p[GC_DOF_Y], dr = (int)p[GC_DOF_R];
  const mjtNum y = d->qpos[m->jnt_qposadr[m->dof_jntid[dy]]];
  const mjtNum phi = d->qpos[m->jnt_qposadr[m->dof_jntid[dr]]];
  const mjtNum vx = d->qvel[dx], vy = d->qvel[dy], w = d->qvel[dr];
  const mjtNum c = p[GC_C], sf = sin(phi), cf = cos(phi), K = p[GC_K], n = p[GC_N];
  mjtNum out[GC_NSENSOR] = {0, 0, 0, 0};
  for (int e = 0; e < 2; e++) {
    const mjtNum s = e == 0 ? p[GC_A] : -p[GC_A];
    const mjtNum rx = s * cf, ry = s * sf;       /* p - Cs */
    const mjtNum py = y + ry;
    const mjtNum pvx = vx - w * ry, pvy = vy + w * rx;
    mjtNum delta = 0, ddelta = 0, sgn = 0;
    if (py > c) { delta = py - c; ddelta = pvy; sgn = -1; }
    else if (py < -c) { delta = -c - py; ddelta = -pvy; sgn = 1; }
    mjtNum fn = 0, ft = 0;
    if (delta > 0) {
      if (st[2 * e] < 0.5) {
        st[2 * e] = 1;
        st[2 * e + 1] = ddelta > p[GC_VMIN] ? ddelta : p[GC_VMIN];
      }
      mjtNum ratio = ddelta / st[2 * e + 1];
      if (ratio < -1.0) ratio = -1.0;
      const mjtNum dn = twin_pow(delta, n);
      fn = K * dn * (1.0 + p[GC_CHI] * ratio);
      if (fn < 0) fn = 0;
      if (fn > 0) ft = gc_friction(p, pvx, fn);
    } else {
      st[2 * e] = 0;
    }
    const mjtNum Fx = ft, Fy = sgn * fn;
    d->qfrc_passive[dx] += Fx;
    d->qfrc_passive[dy] += Fy;
    d->qfrc_passive[dr] += rx * Fy - ry * Fx;
    out[e] = Fy;
    out[2 + e] = Fx;
  }
  const int jr = m->dof_jntid[dr];
  for (int i = 0; i < m->nsensor; i++) {
    if (!twin_user_sensor(m, i, mjOBJ_JOINT, jr, mjSTAGE_POS) || m->sensor_dim[i] < GC_NSENSOR) continue;
    mjtNum* o = d->sensordata + m->sensor_adr[i];
    for (int k = 0; k < GC_NSENSOR; k++) o[k] = out[k];
  }
}
