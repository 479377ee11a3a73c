/* Force effects of a scene: optional stages the model compiles into a list. Private. */
#ifndef FLEX3RPR_EFFECTS_H
#define FLEX3RPR_EFFECTS_H

#include "stages.h"

/* Fills m->effects with the effects the scene enables, in a fixed order. */
void f3r_model_compile_effects(f3r_model* m);

#endif
