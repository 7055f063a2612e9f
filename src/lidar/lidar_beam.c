/* Each beam's scene: a lidar pixel is lit by its own beam only (docs/lidar.md §1), so its camera path sees the
 * scene with the beam template re-aimed along that pixel's axis. A shallow copy of the scene struct per camera
 * sample (a few kilobytes, against the microseconds of a path) keeps every integrator's light loops unchanged. */
#include "dartspp/lidar.h"
#include "dartspp/scene.h"

void lidar_beam_view(const scene *s, size_t px, scene *view, emitter *beam)
{
    *view = *s;
    *beam = s->lights[0];
    int x = (int)(px % (size_t)s->cam.width), y = (int)(px / (size_t)s->cam.width);
    lidar_beam_set(beam, camera_lidar_beam(&s->cam, x, y));
    view->lights = beam;
    view->light_count = 1;
}
