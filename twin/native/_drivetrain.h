/*
 * Drive train of the MuJoCo twin (drive.mode "motor" / "torque"), included by _bore.c: the
 * motor's speed controller on its own encoder and the V-belt's creep/slip law, in the native
 * passive callback, with the same equations as the reference engine (twin/reference/drivetrain.py;
 * the model is described in twin/drivetrain_params.py).
 *
 * The model marks a drive train with a <numeric> whose data start with DT_MAGIC (layout enum
 * dt_field, the one definition on the Python side is twin/names.py DRIVETRAIN_FIELDS, checked at
 * install). Its state lives in mjData.userdata from slot DT_SLOT on (layout enum dt_state), so it
 * is reset with the data, moved by mj_getState/mj_setState(mjSTATE_INTEGRATION) and private to
 * each data object (threads share nothing).
 *
 * Each passive call at the state of step k (time t_k):
 *  1. if time advanced since the last call (a new step), the previous step is completed: belt
 *     stretch x += h xdot, and, if accounting, the work and dissipation of the forces held over
 *     that step with the mean velocity (v_{k-1} + v_k)/2: motor work, belt damping c xdot^2,
 *     creep/slip F w, the guide's friction, and everything else (qfrc_constraint, which still
 *     holds the previous step's, plus the other passive forces) as the joints' dissipation.
 *     A call at the same time (mj_forward after a reset, a re-evaluation) changes nothing.
 *  2. controller sample when k is a multiple of the controller stride (once per k): encoder
 *     count floor(phi counts / 2 pi), speed = count difference / period, first-order low-pass,
 *     PI on set point - estimate, clamp at the peak torque with conditional integration; the
 *     set point is the ctrl of the actuator DT_ACT (a zero-gain actuator that only carries it).
 *     Torque mode: the torque is that ctrl, clamped.
 *  3. belt pull F from x, v_rel = r_m w_m - r_c w_c and v_m (closed form, as belt_pull of the
 *     reference), motor dof gets u - r_m F, crank dof r_c F.
 * User sensors on the motor hinge report the step's values (see drivetrain_sensor).
 */

#include "_native.h"

#define DT_MAGIC 7303.0

enum dt_field {
  DT_MARKER = 0, DT_MOTOR_DOF, DT_CRANK_DOF, DT_ACT, DT_SLOT, DT_MODE, DT_RM, DT_RC, DT_K, DT_C,
  DT_EA, DT_FMAX, DT_CS, DT_STRIDE, DT_COUNTS, DT_ALPHA, DT_KP, DT_KI, DT_TCTRL, DT_PEAK,
  DT_ACCOUNT, DT_GUIDE_DOF, DT_NFIELDS
};
static const char* const dt_field_names[] = {
  "marker", "motor_dof", "crank_dof", "actuator", "slot", "mode", "r_m", "r_c", "k", "c",
  "ea", "f_max", "c_slip", "stride", "counts", "alpha", "kp", "ki", "t_ctrl", "peak",
  "account", "guide_dof"
};
_Static_assert(sizeof(dt_field_names) / sizeof(dt_field_names[0]) == DT_NFIELDS,
               "dt_field_names must name every field of enum dt_field");

enum dt_state {
  DTS_STARTED = 0, DTS_TPREV, DTS_KSAMPLE, DTS_X, DTS_INT, DTS_U, DTS_COUNT, DTS_WF, DTS_F, DTS_W,
  DTS_XDOT, DTS_WORK, DTS_DDAMP, DTS_DSLIP, DTS_DGUIDE, DTS_DCONTACT, DTS_FGUIDE, DTS_VPREV
  /* then nv velocities (DTS_VPREV ..) and nv other passive forces of the previous step */
};
#define DT_NSTATE_FIXED DTS_VPREV
/* dimensions of the two user sensors (see drivetrain_sensor) */
#define DT_NSENSOR_TORQUE 3
#define DT_NSENSOR 7

/* the drive train's numeric data, or NULL */
static const mjtNum* dt_params(const mjModel* m) {
  return twin_numeric(m, DT_MAGIC, DT_NFIELDS);
}

static void dt_belt_pull(const mjtNum* p, mjtNum x, mjtNum vrel, mjtNum vm, mjtNum* F, mjtNum* w) {
  const mjtNum k = p[DT_K], c = p[DT_C], Fmax = p[DT_FMAX], cs = p[DT_CS];
  const mjtNum lam = fabs(vm) / p[DT_EA];
  const mjtNum A = k * x + c * vrel;
  mjtNum f = A / (1.0 + c * lam);
  if (fabs(f) <= Fmax) {
    *F = f;
    *w = lam * f;
  } else {
    const mjtNum sg = A > 0 ? 1.0 : -1.0;
    const mjtNum af = (fabs(A) - c * lam * Fmax + c * Fmax / cs) / (1.0 + c / cs);
    *F = sg * af;
    *w = sg * (lam * Fmax + (af - Fmax) / cs);
  }
}

static mjtNum dt_guide_force(const mjModel* m, const mjData* d, int dof) {
  if (dof < 0 || m->nuser_jnt < GUIDE_NUSER) return 0;
  const int j = m->dof_jntid[dof];
  const mjtNum* user = m->jnt_user + j * m->nuser_jnt;
  if (user[GUIDE_MARKER] != GUIDE_MAGIC) return 0;
  const mjtNum v = d->qvel[dof];
  return twin_oppose(v, user[GUIDE_FORCE] * twin_ramp(fabs(v), user[GUIDE_V0], user[GUIDE_V1]));
}

/* called at the end of the passive callback (every other passive force already in qfrc_passive) */
static void drivetrain_passive(const mjModel* m, mjData* d) {
  const mjtNum* p = dt_params(m);
  if (!p) return;
  const int nv = m->nv, base = (int)p[DT_SLOT];
  if (base < 0 || base + DT_NSTATE_FIXED + 2 * nv > m->nuserdata) return;
  mjtNum* s = d->userdata + base;
  mjtNum* vprev = s + DTS_VPREV;
  mjtNum* fprev = vprev + nv;
  const int dm = (int)p[DT_MOTOR_DOF], dc = (int)p[DT_CRANK_DOF], gdof = (int)p[DT_GUIDE_DOF];
  const mjtNum h = m->opt.timestep;
  const int account = p[DT_ACCOUNT] != 0;
  if (s[DTS_STARTED] != 0 && d->time > s[DTS_TPREV]) {
    /* complete the previous step */
    const mjtNum xd = s[DTS_XDOT];
    s[DTS_X] += h * xd;
    if (account) {
      s[DTS_WORK] += h * s[DTS_U] * 0.5 * (vprev[dm] + d->qvel[dm]);
      s[DTS_DDAMP] += h * p[DT_C] * xd * xd;
      s[DTS_DSLIP] += h * s[DTS_F] * s[DTS_W];
      if (gdof >= 0) s[DTS_DGUIDE] -= h * s[DTS_FGUIDE] * 0.5 * (vprev[gdof] + d->qvel[gdof]);
      mjtNum pw = 0;
      for (int i = 0; i < nv; i++) pw += (d->qfrc_constraint[i] + fprev[i]) * 0.5 * (vprev[i] + d->qvel[i]);
      s[DTS_DCONTACT] -= h * pw;
    }
  }
  /* the state of this step */
  const long k = lround(d->time / h);
  if (p[DT_MODE] == 1.0) {
    const long stride = (long)p[DT_STRIDE];
    if (k % stride == 0 && (s[DTS_STARTED] == 0 || s[DTS_KSAMPLE] != (mjtNum)k)) {
      const mjtNum counts = p[DT_COUNTS], T = p[DT_TCTRL];
      const mjtNum phi = d->qpos[m->jnt_qposadr[m->dof_jntid[dm]]];
      const mjtNum count = floor(phi * counts / (2.0 * mjPI));
      if (s[DTS_STARTED] == 0) s[DTS_COUNT] = count;
      const mjtNum est = (count - s[DTS_COUNT]) * (2.0 * mjPI / counts) / T;
      s[DTS_COUNT] = count;
      s[DTS_WF] += p[DT_ALPHA] * (est - s[DTS_WF]);
      const mjtNum e = d->ctrl[(int)p[DT_ACT]] - s[DTS_WF];
      const mjtNum integ = s[DTS_INT] + p[DT_KI] * T * e;
      mjtNum u = p[DT_KP] * e + integ;
      if (fabs(u) <= p[DT_PEAK]) s[DTS_INT] = integ;
      else u = u > 0 ? p[DT_PEAK] : -p[DT_PEAK];
      s[DTS_U] = u;
      s[DTS_KSAMPLE] = (mjtNum)k;
    }
  } else {
    const mjtNum u = d->ctrl[(int)p[DT_ACT]], pk = p[DT_PEAK];
    s[DTS_U] = u > pk ? pk : (u < -pk ? -pk : u);
  }
  const mjtNum vm = p[DT_RM] * d->qvel[dm];
  mjtNum F, w;
  dt_belt_pull(p, s[DTS_X], vm - p[DT_RC] * d->qvel[dc], vm, &F, &w);
  s[DTS_F] = F;
  s[DTS_W] = w;
  s[DTS_XDOT] = vm - p[DT_RC] * d->qvel[dc] - w;
  if (account) {
    for (int i = 0; i < nv; i++) {
      vprev[i] = d->qvel[i];
      fprev[i] = d->qfrc_passive[i];
    }
    s[DTS_FGUIDE] = dt_guide_force(m, d, gdof);
    if (gdof >= 0) fprev[gdof] -= s[DTS_FGUIDE];
  } else {
    vprev[dm] = d->qvel[dm];
  }
  d->qfrc_passive[dm] += s[DTS_U] - p[DT_RM] * F;
  d->qfrc_passive[dc] += p[DT_RC] * F;
  s[DTS_STARTED] = 1;
  s[DTS_TPREV] = d->time;
  /* the position-stage user sensor on the motor hinge: MuJoCo computed (zeroed) it before this
   * velocity-stage callback and leaves it alone afterwards, so no acceleration-stage sensor pass
   * is needed for these */
  const int jm = m->dof_jntid[dm];
  for (int i = 0; i < m->nsensor; i++) {
    if (!twin_user_sensor(m, i, mjOBJ_JOINT, jm, mjSTAGE_POS) || m->sensor_dim[i] < DT_NSENSOR_TORQUE) continue;
    mjtNum* out = d->sensordata + m->sensor_adr[i];
    out[0] = s[DTS_U];
    out[1] = p[DT_RC] * F;
    out[2] = w;
  }
}

/* user sensors on the motor hinge: needstage "pos", written by the passive callback: motor
 * torque, belt torque on the crank, slip speed; needstage "acc" (the accounts, after MuJoCo's
 * energies): motor work, belt energy, dissipation (damping, slip, guide, joints), energy of the
 * mechanism and the rotor */

static void drivetrain_sensor(const mjModel* m, mjData* d, int stage) {
  if (stage != mjSTAGE_ACC) return;
  const mjtNum* p = dt_params(m);
  if (!p) return;
  const int nv = m->nv, base = (int)p[DT_SLOT];
  if (base < 0 || base + DT_NSTATE_FIXED + 2 * nv > m->nuserdata) return;
  const mjtNum* s = d->userdata + base;
  const int jm = m->dof_jntid[(int)p[DT_MOTOR_DOF]];
  for (int i = 0; i < m->nsensor; i++) {
    if (!twin_user_sensor(m, i, mjOBJ_JOINT, jm, mjSTAGE_ACC) || m->sensor_dim[i] < DT_NSENSOR) continue;
    mjtNum* out = d->sensordata + m->sensor_adr[i];
    out[0] = s[DTS_WORK];
    out[1] = 0.5 * p[DT_K] * s[DTS_X] * s[DTS_X];
    out[2] = s[DTS_DDAMP];
    out[3] = s[DTS_DSLIP];
    out[4] = s[DTS_DGUIDE];
    out[5] = s[DTS_DCONTACT];
    out[6] = d->energy[0] + d->energy[1];
  }
}
