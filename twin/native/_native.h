/*
 * Helpers shared by the twin's native code (_bore.c, _socket.c, _guide.h, _drivetrain.h): the one
 * copy of each small law and look-up they all use. Everything here is a pure function of its
 * arguments (model, data, numbers): no state.
 */
#ifndef TWIN_NATIVE_H
#define TWIN_NATIVE_H

#include <math.h>
#include <stdint.h>
#include <string.h>
#include <mujoco/mujoco.h>

/* marker of a bore (cylinder) or socket (sphere) in geom user data field 0 (twin/names.py BORE_MAGIC) */
#define BORE_MAGIC 7301.0

/* Adams' cubic STEP: h0 for x <= x0, h1 for x >= x1, h0 + (h1 - h0) D^2 (3 - 2 D) between */
static inline mjtNum twin_step3(mjtNum x, mjtNum x0, mjtNum h0, mjtNum x1, mjtNum h1) {
  if (x <= x0) return h0;
  if (x >= x1) return h1;
  const mjtNum dd = (x - x0) / (x1 - x0);
  return h0 + (h1 - h0) * dd * dd * (3.0 - 2.0 * dd);
}

/* The regularization of Coulomb friction (S003 Eq. 19-20) at slip speed s = |v| >= 0 [m/s]: 0 below
 * v0, 1 above v1, linear between. Two roundings of the same ramp are in use and kept (they differ
 * in the last bit): twin_ramp is the fraction, which a guide multiplies by its force (F r);
 * twin_ramp_scaled(f, ...) multiplies before dividing (f (s - v0) / (v1 - v0)), the bore's friction
 * coefficient. */
static inline mjtNum twin_ramp(mjtNum s, mjtNum v0, mjtNum v1) {
  if (s >= v1) return 1;
  if (s > v0) return (s - v0) / (v1 - v0);
  return 0;
}

static inline mjtNum twin_ramp_scaled(mjtNum f, mjtNum s, mjtNum v0, mjtNum v1) {
  if (s >= v1) return f;
  if (s > v0) return f * (s - v0) / (v1 - v0);
  return 0;
}

/* a force of magnitude f opposing the speed v (0 at v = 0) */
static inline mjtNum twin_oppose(mjtNum v, mjtNum f) {
  return v > 0 ? -f : (v < 0 ? f : 0.0);
}

/* delta^n, exact for the Hertzian n = 1.5 */
static inline mjtNum twin_pow(mjtNum delta, mjtNum n) {
  return n == 1.5 ? delta * sqrt(delta) : pow(delta, n);
}

/* the data of the model's first <numeric> with at least nfields values whose first is magic, or NULL */
static inline const mjtNum* twin_numeric(const mjModel* m, mjtNum magic, int nfields) {
  for (int i = 0; i < m->nnumeric; i++) {
    if (m->numeric_size[i] >= nfields && m->numeric_data[m->numeric_adr[i]] == magic)
      return m->numeric_data + m->numeric_adr[i];
  }
  return NULL;
}

/* whether sensor i is a user sensor of object (objtype, objid) computed at stage */
static inline int twin_user_sensor(const mjModel* m, int i, int objtype, int objid, int stage) {
  return m->sensor_type[i] == mjSENS_USER && m->sensor_objtype[i] == objtype && m->sensor_objid[i] == objid &&
         m->sensor_needstage[i] == stage;
}

/* MuJoCo functions the native code calls, found in the library the mujoco module loaded (the extension
 * does not link it): set once by install(), the same for every model */
typedef void (*twin_applyFT_t)(const mjModel*, mjData*, const mjtNum*, const mjtNum*, const mjtNum*, int, mjtNum*);
typedef void (*twin_solveM_t)(const mjModel*, mjData*, mjtNum*, const mjtNum*, int);

#endif
