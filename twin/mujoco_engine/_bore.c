/*
 * Native "pin inside a bore" collider for the twin's clearance joints.
 *
 * MuJoCo has no concave primitive, so a bushing (a hollow cylinder) cannot be a geom. Its
 * documented extension point is the global collision table mjCOLLISIONFUNC[type1][type2]
 * (MuJoCo docs, programming/simulation "Collision detection"). This module installs a
 * function for the cylinder-cylinder pair: when exactly one of the two geoms is marked as a
 * bore (geom user data field marker == BORE_MAGIC), the pair is treated as a pin of radius R_j inside a bore
 * of radius R_i (both taken from geom_size[0]) with parallel axes (the bore's z axis):
 *
 *   e    = pin centre - bore centre, projected on the plane normal to the bore axis
 *   dist = (R_i - R_j) - |e|            (> 0: gap; < 0: penetration)
 *   n    = e / |e|                       (from the bore centre towards the contact)
 *
 * One contact at the midpoint between the two surfaces along n, normal pointing from
 * geom1 to geom2 (MuJoCo's convention), first tangent = axis x normal (in the plane of
 * motion). The geometry is an exact circle: no faceting error, whatever the clearance.
 * Every other cylinder-cylinder pair is passed to the function that was in the table before
 * (MuJoCo's own), so unmarked models behave as usual. The collider is stateless and
 * thread-safe (it works under mujoco.rollout with several threads).
 *
 * Friction. The pair is a frictionless (condim 1) MuJoCo contact: MuJoCo's soft elliptic cone
 * adds mu * (would-be sticking force) to the normal force while sliding, which inflated the
 * normal force by a median 23 % and up to 27x on the bench (measured, see the builder's
 * docstring). Friction is applied instead as a passive force (mjcb_passive), exactly the
 * reference's regularized Coulomb law (S003 Eq. 19-20):
 *
 *   f_T = mu(v_r) f_N,  mu = 0 below v0, mu0 (v_r - v0)/(v1 - v0) between, mu0 above v1,
 *
 * opposing the tangential relative velocity v_r of the contact points on the pin and on the
 * bore (rotations included). f_N is the contact's soft-constraint force predicted from its
 * own row, f_N = aref / (A_hat + R) with aref = -B vel - K I pos (MuJoCo's reference
 * acceleration, impedance I): exactly k d + c d' for a flat, tiny impedance. The bore geom's
 * user data carry the law: fields BORE_MU0, BORE_V0, BORE_V1 (enum bore_user). A user sensor (mjcb_sensor,
 * objtype geom = the bore) reports the friction force on the pin along t = axis x n, where
 * n points from the bore centre towards the pin.
 *
 * Impact-speed damping (optional: user[BORE_DAMPING_COEF] > 0, nuser_geom >= BORE_NUSER). The reference's
 * Lankarani-Nikravesh law damps with chi K d^n d'/v_imp, v_imp the approach speed stored at
 * the start of the contact event (S003 Eq. 17), which a fixed solref cannot express. Here,
 * in mjcb_passive (after MuJoCo has built the constraint rows, before it computes their
 * reference accelerations), the damping B of the bore's first contact row is raised by
 *
 *   B_x = coef d^n / v_imp * (A_hat + R),   coef = user[BORE_DAMPING_COEF], n = user[BORE_EXPONENT],
 *
 * which adds coef d^n d'/v_imp to that row's force and lets the solver treat it implicitly
 * (no explicit-damping step limit). v_imp = max(approach speed, user[BORE_SPEED_FLOOR]) is taken when the
 * bore has a contact and had none at the previous call, and kept in d->userdata[user[BORE_SLOT]]
 * (0 = no event; mj_resetData clears it). As in the reference, the ratio d'/v_imp is kept
 * above -1 while separating. Assumes one mjcb_passive call per constraint build (mj_step,
 * mj_forward; not mj_forwardSkip from the velocity stage).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <mujoco/mujoco.h>

#define BORE_MAGIC 7301.0

/* Layout of a bore geom's user data (m->geom_user row, nuser_geom = BORE_NUSER): the one
 * definition is twin/names.py BORE_USERDATA_FIELDS (same names, same order). The module reports
 * its layout (userdata_fields()) and twin/mujoco_engine/collider.py refuses to install it if
 * the two differ. */
enum bore_user {
  BORE_MARKER = 0,       /* BORE_MAGIC marks the geom as a bore */
  BORE_MU0,              /* regularized Coulomb friction: mu0 [-] (0 = off) */
  BORE_V0,               /* v0 [m/s]: mu = 0 below */
  BORE_V1,               /* v1 [m/s]: mu = mu0 above */
  BORE_DAMPING_COEF,     /* impact-speed damping coef = chi K [N/m^n] (0 = off) */
  BORE_EXPONENT,         /* its exponent n [-] */
  BORE_SPEED_FLOOR,      /* floor of the stored impact speed [m/s] */
  BORE_SLOT,             /* d->userdata index that keeps v_imp (-1 = none) */
  BORE_NUSER             /* number of fields */
};
static const char* const bore_user_names[] = {
  "marker", "mu0", "v0", "v1", "damping_coef", "exponent", "speed_floor", "slot"
};
_Static_assert(sizeof(bore_user_names) / sizeof(bore_user_names[0]) == BORE_NUSER,
               "bore_user_names must name every field of enum bore_user");

static mjfCollision g_previous = NULL;
static mjfGeneric g_prev_passive = NULL;
static mjfSensor g_prev_sensor = NULL;
typedef void (*applyFT_t)(const mjModel*, mjData*, const mjtNum*, const mjtNum*, const mjtNum*, int, mjtNum*);
static applyFT_t g_applyFT = NULL;
static int g_installed = 0;

static int is_bore(const mjModel* m, int g) {
  return m->nuser_geom > BORE_MARKER && m->geom_user[g * m->nuser_geom + BORE_MARKER] == BORE_MAGIC;
}

static int collide_pin_bore(const mjModel* m, mjData* d, mjPreContact* con,
                            int g1, int g2, mjtNum margin) {
  int b1 = is_bore(m, g1), b2 = is_bore(m, g2);
  if (b1 == b2) {
    return g_previous ? g_previous(m, d, con, g1, g2, margin) : 0;
  }
  int gb = b1 ? g1 : g2, gp = b1 ? g2 : g1;
  const mjtNum* xb = d->geom_xpos + 3 * gb;
  const mjtNum* xp = d->geom_xpos + 3 * gp;
  const mjtNum* R = d->geom_xmat + 9 * gb;
  const mjtNum a[3] = {R[2], R[5], R[8]};        /* bore axis (geom z) in world */
  mjtNum e[3] = {xp[0] - xb[0], xp[1] - xb[1], xp[2] - xb[2]};
  const mjtNum ea = e[0] * a[0] + e[1] * a[1] + e[2] * a[2];
  e[0] -= ea * a[0];
  e[1] -= ea * a[1];
  e[2] -= ea * a[2];
  const mjtNum ecc = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
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

typedef struct {
  int pin_body, bore_body;
  mjtNum t[3];   /* in-plane tangent axis x n (n: bore centre -> pin) */
  mjtNum fn;     /* predicted normal force [N] */
  mjtNum ft;     /* friction force on the pin along t [N] */
} friction_t;

/* friction of contact icon if it is an active pin/bore contact; returns 0 otherwise */
static int bore_friction(const mjModel* m, const mjData* d, int icon, friction_t* out) {
  const mjContact* con = d->contact + icon;
  const int g1 = con->geom[0], g2 = con->geom[1];
  if (g1 < 0 || g2 < 0) return 0;
  const int b1 = is_bore(m, g1), b2 = is_bore(m, g2);
  if (b1 == b2 || con->exclude || con->efc_address < 0) return 0;
  const int gb = b1 ? g1 : g2, gp = b1 ? g2 : g1;
  if (m->nuser_geom <= BORE_V1) return 0;
  const mjtNum* user = m->geom_user + gb * m->nuser_geom;
  const mjtNum mu0 = user[BORE_MU0], v0 = user[BORE_V0], v1 = user[BORE_V1];
  const int row = con->efc_address;
  const mjtNum* kbip = d->efc_KBIP + 4 * row;
  mjtNum va[3], vb[3];
  const mjtNum vel = contact_velocity(m, d, con, va, vb);
  const mjtNum* n12 = con->frame;               /* from geom1 to geom2 */
  const mjtNum aref = -kbip[1] * vel - kbip[0] * kbip[2] * (d->efc_pos[row] - d->efc_margin[row]);
  const mjtNum fn = aref / (d->efc_diagA[row] + d->efc_R[row]);
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
  const mjtNum vt = (vpin[0] - vbore[0]) * out->t[0] + (vpin[1] - vbore[1]) * out->t[1] +
                    (vpin[2] - vbore[2]) * out->t[2];
  const mjtNum s = fabs(vt);
  mjtNum mu = 0;
  if (s >= v1) mu = mu0;
  else if (s > v0) mu = mu0 * (s - v0) / (v1 - v0);
  out->ft = vt > 0 ? -mu * out->fn : (vt < 0 ? mu * out->fn : 0.0);
  return 1;
}

static void impact_speed_damping(const mjModel* m, mjData* d) {
  const int nu = m->nuser_geom;
  if (nu < BORE_NUSER) return;
  for (int gb = 0; gb < m->ngeom; gb++) {
    const mjtNum* user = m->geom_user + gb * nu;
    if (user[BORE_MARKER] != BORE_MAGIC || !(user[BORE_DAMPING_COEF] > 0)) continue;
    const int slot = (int)user[BORE_SLOT];
    if (slot < 0 || slot >= m->nuserdata) continue;
    int icon = -1;
    for (int i = 0; i < d->ncon; i++) {
      const mjContact* con = d->contact + i;
      if ((con->geom[0] == gb || con->geom[1] == gb) && !con->exclude && con->efc_address >= 0) {
        icon = i;
        break;
      }
    }
    if (icon < 0) {
      d->userdata[slot] = 0;
      continue;
    }
    const int row = d->contact[icon].efc_address;
    mjtNum va[3], vb[3];
    const mjtNum vel = contact_velocity(m, d, d->contact + icon, va, vb);
    if (!(d->userdata[slot] > 0)) d->userdata[slot] = fmax(-vel, user[BORE_SPEED_FLOOR]);
    const mjtNum vimp = d->userdata[slot];
    const mjtNum pen = -(d->efc_pos[row] - d->efc_margin[row]);
    if (!(pen > 0)) continue;
    mjtNum b = user[BORE_DAMPING_COEF] * pow(pen, user[BORE_EXPONENT]) / vimp * (d->efc_diagA[row] + d->efc_R[row]);
    const mjtNum ratio = -vel / vimp;           /* d'/v_imp */
    if (ratio < -1) b /= -ratio;                /* clamp: force as at d'/v_imp = -1 */
    d->efc_KBIP[4 * row + 1] += b;
  }
}

static void passive_friction(const mjModel* m, mjData* d) {
  if (g_prev_passive) g_prev_passive(m, d);
  impact_speed_damping(m, d);
  if (!g_applyFT || m->nuser_geom <= BORE_V1) return;
  for (int i = 0; i < d->ncon; i++) {
    friction_t f;
    if (!bore_friction(m, d, i, &f) || f.ft == 0) continue;
    const mjtNum F[3] = {f.ft * f.t[0], f.ft * f.t[1], f.ft * f.t[2]};
    const mjtNum Fm[3] = {-F[0], -F[1], -F[2]};
    g_applyFT(m, d, F, NULL, d->contact[i].pos, f.pin_body, d->qfrc_passive);
    g_applyFT(m, d, Fm, NULL, d->contact[i].pos, f.bore_body, d->qfrc_passive);
  }
}

static void sensor_friction(const mjModel* m, mjData* d, int stage) {
  if (g_prev_sensor) g_prev_sensor(m, d, stage);
  if (stage != mjSTAGE_VEL || m->nuser_geom <= BORE_V1) return;
  for (int s = 0; s < m->nsensor; s++) {
    if (m->sensor_type[s] != mjSENS_USER || m->sensor_objtype[s] != mjOBJ_GEOM) continue;
    const int gb = m->sensor_objid[s];
    if (gb < 0 || !is_bore(m, gb)) continue;
    mjtNum value = 0;  /* summed over the bore's contacts (one per term of the contact law) */
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
  unsigned long long table_addr, passive_addr, sensor_addr, applyft_addr;
  if (!PyArg_ParseTuple(args, "KKKK", &table_addr, &passive_addr, &sensor_addr, &applyft_addr)) return NULL;
  if (!table_addr || !passive_addr || !sensor_addr || !applyft_addr) {
    PyErr_SetString(PyExc_ValueError, "null address");
    return NULL;
  }
  mjfCollision (*table)[mjNGEOMTYPES] = (mjfCollision (*)[mjNGEOMTYPES])(uintptr_t)table_addr;
  mjfGeneric* passive = (mjfGeneric*)(uintptr_t)passive_addr;
  mjfSensor* sensor = (mjfSensor*)(uintptr_t)sensor_addr;
  int changed = 0;
  g_applyFT = (applyFT_t)(uintptr_t)applyft_addr;
  /* (re)install each hook that is not ours, chaining what was there */
  if (table[mjGEOM_CYLINDER][mjGEOM_CYLINDER] != collide_pin_bore) {
    g_previous = table[mjGEOM_CYLINDER][mjGEOM_CYLINDER];
    table[mjGEOM_CYLINDER][mjGEOM_CYLINDER] = collide_pin_bore;
    changed = 1;
  }
  if (*passive != passive_friction) {
    g_prev_passive = *passive;
    *passive = passive_friction;
    changed = 1;
  }
  if (*sensor != sensor_friction) {
    g_prev_sensor = *sensor;
    *sensor = sensor_friction;
    changed = 1;
  }
  g_installed = 1;
  if (changed) Py_RETURN_TRUE;
  Py_RETURN_FALSE;
}

static PyObject* py_header_version(PyObject* self, PyObject* args) {
  return PyLong_FromLong(mjVERSION_HEADER);
}

static PyObject* py_bore_magic(PyObject* self, PyObject* args) {
  return PyFloat_FromDouble(BORE_MAGIC);
}

static PyObject* py_userdata_fields(PyObject* self, PyObject* args) {
  PyObject* out = PyTuple_New(BORE_NUSER);
  if (!out) return NULL;
  for (int i = 0; i < BORE_NUSER; i++) {
    PyObject* name = PyUnicode_FromString(bore_user_names[i]);
    if (!name) {
      Py_DECREF(out);
      return NULL;
    }
    PyTuple_SET_ITEM(out, i, name);
  }
  return out;
}

static PyMethodDef methods[] = {
  {"install", py_install, METH_VARARGS, "install(table, passive, sensor, applyFT): addresses of mjCOLLISIONFUNC, mjcb_passive, mjcb_sensor and the function mj_applyFT."},
  {"header_version", py_header_version, METH_NOARGS, "mjVERSION_HEADER the module was compiled against."},
  {"bore_magic", py_bore_magic, METH_NOARGS, "geom user data marker value that marks a bore."},
  {"userdata_fields", py_userdata_fields, METH_NOARGS, "names of the bore geom's user data fields, in order (enum bore_user)."},
  {NULL, NULL, 0, NULL}
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_bore", NULL, -1, methods};

PyMODINIT_FUNC PyInit__bore(void) { return PyModule_Create(&module); }
