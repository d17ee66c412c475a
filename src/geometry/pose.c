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

int sasnav_array_check(const sasnav_array *array)
{
    if (!array) return sasnav_set_error(SASNAV_ERR_ARG, "array description is NULL");
    if (array->n_rx < 1 || array->n_rx > SASNAV_MAX_RX)
        return sasnav_set_error(SASNAV_ERR_ARG, "array needs 1..%d receivers, got %d",
                                SASNAV_MAX_RX, array->n_rx);
    if (!isfinite(array->rx_length) || array->rx_length < 0 || !isfinite(array->tx_length) ||
        array->tx_length < 0)
        return sasnav_set_error(SASNAV_ERR_ARG, "element lengths must be finite and >= 0");
    if (!isfinite(array->rx_height) || !isfinite(array->tx_height))
        return sasnav_set_error(SASNAV_ERR_ARG, "sensor heights must be finite");
    for (int l = 0; l < array->n_rx; l++)
        if (!isfinite(array->rx_u[l]))
            return sasnav_set_error(SASNAV_ERR_ARG, "receiver %d position is not finite", l);
    return SASNAV_OK;
}

int sasnav_array_uniform(sasnav_array *array, int n, double spacing, double length,
                         double tx_length)
{
    if (!array) return sasnav_set_error(SASNAV_ERR_ARG, "array is NULL");
    if (n < 1 || n > SASNAV_MAX_RX)
        return sasnav_set_error(SASNAV_ERR_ARG, "array needs 1..%d receivers, got %d",
                                SASNAV_MAX_RX, n);
    if (!(spacing > 0) || !isfinite(spacing))
        return sasnav_set_error(SASNAV_ERR_ARG, "receiver spacing must be > 0, got %g", spacing);
    sasnav_array a = {0};
    a.n_rx = n;
    for (int l = 0; l < n; l++) a.rx_u[l] = (l - 0.5 * (n - 1)) * spacing;
    a.rx_length = length;
    a.tx_length = tx_length;
    int rc = sasnav_array_check(&a);
    if (rc) return rc;
    *array = a;
    return SASNAV_OK;
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
