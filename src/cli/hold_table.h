/* The --hold table (T:INDEX:VALUE): a controller's commands known ahead, held from output time
 * to output time exactly as the node holds its commands, and checked by the session's rule. */
#ifndef FLEX3RPR_CLI_HOLD_TABLE_H
#define FLEX3RPR_CLI_HOLD_TABLE_H

#include "cli_options.h"
#include "flex3rpr/model.h"
#include "flex3rpr/scene.h"
#include "flex3rpr/sim.h"

/* 0 when a hold's index is beyond the model or the command it leaves is refused (said). */
int cli_check_holds(const cli_options* o, const f3r_scene* scene, const f3r_model* model);
/* The holds due at the simulation's time into held, and into the simulation when they change. */
f3r_status cli_apply_holds(const cli_options* o, double output_step, f3r_sim* sim, double* held,
                           f3r_error* err);

#endif
