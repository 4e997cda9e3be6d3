/*
 * Native "pin inside a bore" collider for the twin's clearance joints.
 *
 * MuJoCo has no concave primitive, so a bushing (a hollow cylinder) cannot be a geom. Its
 * documented extension point is the global collision table mjCOLLISIONFUNC[type1][type2]
 * (MuJoCo docs, programming/simulation "Collision detection"). This module installs a
 * function for the cylinder-cylinder pair: when exactly one of the two geoms is marked as a
 * bore (geom user[0] == BORE_MAGIC), the pair is treated as a pin of radius R_j inside a bore
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
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <mujoco/mujoco.h>

#define BORE_MAGIC 7301.0

static mjfCollision g_previous = NULL;
static int g_installed = 0;

static int is_bore(const mjModel* m, int g) {
  return m->nuser_geom > 0 && m->geom_user[g * m->nuser_geom] == BORE_MAGIC;
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

/* install(table_address) -> True if installed now, False if it already was */
static PyObject* py_install(PyObject* self, PyObject* args) {
  unsigned long long addr;
  if (!PyArg_ParseTuple(args, "K", &addr)) return NULL;
  if (addr == 0) {
    PyErr_SetString(PyExc_ValueError, "null collision table address");
    return NULL;
  }
  mjfCollision (*table)[mjNGEOMTYPES] = (mjfCollision (*)[mjNGEOMTYPES])(uintptr_t)addr;
  if (table[mjGEOM_CYLINDER][mjGEOM_CYLINDER] == collide_pin_bore) Py_RETURN_FALSE;
  g_previous = table[mjGEOM_CYLINDER][mjGEOM_CYLINDER];
  table[mjGEOM_CYLINDER][mjGEOM_CYLINDER] = collide_pin_bore;
  g_installed = 1;
  Py_RETURN_TRUE;
}

static PyObject* py_header_version(PyObject* self, PyObject* args) {
  return PyLong_FromLong(mjVERSION_HEADER);
}

static PyObject* py_bore_magic(PyObject* self, PyObject* args) {
  return PyFloat_FromDouble(BORE_MAGIC);
}

static PyMethodDef methods[] = {
  {"install", py_install, METH_VARARGS, "Install the pin/bore collider into mjCOLLISIONFUNC at the given address."},
  {"header_version", py_header_version, METH_NOARGS, "mjVERSION_HEADER the module was compiled against."},
  {"bore_magic", py_bore_magic, METH_NOARGS, "geom user[0] value that marks a bore."},
  {NULL, NULL, 0, NULL}
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_bore", NULL, -1, methods};

PyMODINIT_FUNC PyInit__bore(void) { return PyModule_Create(&module); }
