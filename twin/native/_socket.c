/*
 * Native "ball inside a socket" collider for the spherical clearance joints of the spatial
 * slider-crank (S002), compiled into the same extension as _bore.c and installed by its
 * install() (twin_socket_install).
 *
 * MuJoCo has no concave primitive, so a socket (a hollow sphere) cannot be a geom. This
 * collider takes the sphere-sphere pair of the global table mjCOLLISIONFUNC: when exactly one
 * of the two spheres is marked as a socket (BORE_MAGIC, the bore marker, in geom user data field
 * 0), the pair is a ball of radius R_b inside a socket of radius R_s (both geom_size[0]):
 *
 *   e    = ball centre - socket centre (3D)
 *   dist = (R_s - R_b) - |e|            (> 0: gap; < 0: penetration delta = -dist)
 *   n    = e / |e|
 *
 * One contact, normal from geom1 to geom2 (MuJoCo's convention) along the centre line, placed at
 * the ball's centre: the normal force passes through both centres wherever the point is on that
 * line, and the friction of _bore.c (which takes the sliding velocity at the contact point) then
 * slides on the velocity of the ball's centre relative to the socket's body at that point, the
 * reference engine's definition (twin/spatial/model.py: its rod has no spin). The contact law
 * and the friction are those of _bore.c, which treats a marked sphere as a socket (no bore
 * axis). Every other sphere-sphere pair goes to the function that was in the table before
 * (MuJoCo's own). Stateless and thread-safe: the collider reads everything from the model and
 * data it is given.
 */
#include "_native.h"

/* the sphere-sphere collider that was in the table when this one was installed (MuJoCo's own) */
static mjfCollision g_prev_sphere = NULL;

static int is_socket(const mjModel* m, int g) {
  return m->nuser_geom >= 1 && m->geom_type[g] == mjGEOM_SPHERE && m->geom_user[g * m->nuser_geom] == BORE_MAGIC;
}

static int collide_ball_socket(const mjModel* m, mjData* d, mjPreContact* con, int g1, int g2, mjtNum margin) {
  const int s1 = is_socket(m, g1), s2 = is_socket(m, g2);
  if (s1 == s2) {
    return g_prev_sphere ? g_prev_sphere(m, d, con, g1, g2, margin) : 0;
  }
  const int gs = s1 ? g1 : g2, gb = s1 ? g2 : g1;
  const mjtNum* xs = d->geom_xpos + 3 * gs;
  const mjtNum* xb = d->geom_xpos + 3 * gb;
  const mjtNum e[3] = {xb[0] - xs[0], xb[1] - xs[1], xb[2] - xs[2]};
  const mjtNum ecc = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  const mjtNum dist = (m->geom_size[3 * gs] - m->geom_size[3 * gb]) - ecc;
  if (dist > margin) return 0;
  mjtNum n[3] = {1, 0, 0};
  if (ecc > 1e-300) {
    n[0] = e[0] / ecc; n[1] = e[1] / ecc; n[2] = e[2] / ecc;
  }
  const mjtNum sg = s1 ? -1.0 : 1.0;            /* normal from geom1 to geom2 (as _bore.c: -n if geom1 is the socket) */
  con->dist = dist;
  con->pos[0] = xb[0];
  con->pos[1] = xb[1];
  con->pos[2] = xb[2];
  con->normal[0] = sg * n[0];
  con->normal[1] = sg * n[1];
  con->normal[2] = sg * n[2];
  /* a tangent: normal x the world axis least aligned with it */
  const mjtNum* nn = con->normal;
  int k = fabs(nn[0]) < fabs(nn[1]) ? (fabs(nn[0]) < fabs(nn[2]) ? 0 : 2) : (fabs(nn[1]) < fabs(nn[2]) ? 1 : 2);
  mjtNum ax[3] = {0, 0, 0};
  ax[k] = 1;
  mjtNum t[3] = {nn[1] * ax[2] - nn[2] * ax[1], nn[2] * ax[0] - nn[0] * ax[2], nn[0] * ax[1] - nn[1] * ax[0]};
  const mjtNum tl = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  con->tangent[0] = t[0] / tl;
  con->tangent[1] = t[1] / tl;
  con->tangent[2] = t[2] / tl;
  return 1;
}

/* the unit sliding direction t of a socket contact (relative velocity of the ball's point minus
 * the socket's, its normal part removed; n any unit normal); t = 0 without sliding */
void twin_socket_tangent(const mjtNum vball[3], const mjtNum vsocket[3], const mjtNum n[3], mjtNum t[3]) {
  mjtNum v[3] = {vball[0] - vsocket[0], vball[1] - vsocket[1], vball[2] - vsocket[2]};
  const mjtNum vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
  for (int i = 0; i < 3; i++) v[i] -= vn * n[i];
  const mjtNum s = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int i = 0; i < 3; i++) t[i] = s > 0 ? v[i] / s : 0;
}

/* install the collider in table[sphere][sphere] (table: mjCOLLISIONFUNC), chaining what was
 * there. Returns 1 if it changed the table. */
int twin_socket_install(void* table_addr) {
  mjfCollision (*table)[mjNGEOMTYPES] = (mjfCollision (*)[mjNGEOMTYPES])table_addr;
  if (table[mjGEOM_SPHERE][mjGEOM_SPHERE] != collide_ball_socket) {
    g_prev_sphere = table[mjGEOM_SPHERE][mjGEOM_SPHERE];
    table[mjGEOM_SPHERE][mjGEOM_SPHERE] = collide_ball_socket;
    return 1;
  }
  return 0;
}
