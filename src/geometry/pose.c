/* SE(2) poses, array descriptions and ping centroids (SPEC 1). */
#include "sasnav/geometry.h"
#include "sasnav/error.h"

#include <math.h>

sasnav_pose sasnav_pose_compose(sasnav_pose a, sasnav_pose b)
{
    double c = cos(a.theta), s = sin(a.theta);
    sasnav_pose r = {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y,
                     sasnav_wrap_angle(a.theta + b.theta)};
    return r;
}

sasnav_pose sasnav_pose_inverse(sasnav_pose a)
{
    double c = cos(a.theta), s = sin(a.theta);
    sasnav_pose r = {-(c * a.x + s * a.y), -(-s * a.x + c * a.y), sasnav_wrap_angle(-a.theta)};
    return r;
}

sasnav_pose sasnav_pose_between(sasnav_pose p, sasnav_pose q)
{
    return sasnav_pose_compose(sasnav_pose_inverse(p), q);
}

void sasnav_pose_apply(sasnav_pose a, double px, double py, double *wx, double *wy)
{
    double c = cos(a.theta), s = sin(a.theta);
    *wx = a.x + c * px - s * py;
    *wy = a.y + s * px + c * py;
}

double sasnav_wrap_angle(double theta)
{
    double t = fmod(theta + M_PI, 2.0 * M_PI);
    if (t <= 0.0) t += 2.0 * M_PI;
    return t - M_PI;
}

sasnav_pose sasnav_ping_centroid(const sasnav_ping_pose *ping)
{
    sasnav_pose c = {0.5 * (ping->array.x + ping->tx.x), 0.5 * (ping->array.y + ping->tx.y),
                     ping->array.theta};
    return c;
}

sasnav_pose sasnav_ping_displacement(const sasnav_ping_pose *p, const sasnav_ping_pose *q)
{
    return sasnav_pose_between(sasnav_ping_centroid(p), sasnav_ping_centroid(q));
}

sasnav_ping_pose sasnav_ping_local(const sasnav_ping_pose *ping)
{
    sasnav_pose c = sasnav_ping_centroid(ping);
    sasnav_ping_pose local = {sasnav_pose_between(c, ping->tx), sasnav_pose_between(c, ping->array)};
    return local;
}

sasnav_ping_pose sasnav_ping_place(sasnav_pose centroid, const sasnav_ping_pose *local)
{
    sasnav_ping_pose w = {sasnav_pose_compose(centroid, local->tx),
                          sasnav_pose_compose(centroid, local->array)};
    return w;
}

sasnav_ping_pose sasnav_epca_local(double tx_lag, double dtheta_tx)
{
    sasnav_ping_pose local = {{-0.5 * tx_lag, 0.0, dtheta_tx}, {0.5 * tx_lag, 0.0, 0.0}};
    return local;
}

double sasnav_motion_tx_lag(double speed, double range, double sound_speed)
{
    return speed * 2.0 * range / sound_speed;
}

void sasnav_channel_poses(const sasnav_ping_pose *ping, const sasnav_ping_pose *offset, int n,
                          sasnav_ping_pose *out)
{
    for (int l = 0; l < n; l++) {
        out[l].tx = sasnav_pose_compose(ping->tx, offset[l].tx);
        out[l].array = sasnav_pose_compose(ping->array, offset[l].array);
    }
}

double sasnav_channel_offset_radius(const sasnav_ping_pose *offset, int n)
{
    double r = 0;
    for (int l = 0; offset && l < n; l++) {
        r = fmax(r, hypot(offset[l].tx.x, offset[l].tx.y));
        r = fmax(r, hypot(offset[l].array.x, offset[l].array.y));
    }
    return r;
}
