/* check_rig.c: every readiness check of the parts a rig file's mode uses, in the order a lab
 * fixes them: rails (ports, locks, settings, state, limits), camera, store, disk. Replay mode has
 * no rails, camera or video of its own: the store, and the free disk where it is. */
#include "check.h"

check_env check_env_default(void)
{
    check_env e = {0};
    e.service_user = NULL;
    e.trials = CHECK_TRIALS;
    return e;
}

void check_rig_run(const rig_config *cfg, const check_env *env, check_report *r)
{
    if (cfg->mode != RIG_MODE_REPLAY) {
        check_rails(cfg, env, r);
        check_camera(cfg, env, r);
    }
    check_store(cfg, env, r);
    if (cfg->mode != RIG_MODE_REPLAY) check_disk(cfg, env, r);
    else check_store_disk(cfg, env, r);
}
