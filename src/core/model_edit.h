/* Building a model from an edited copy of a scene, in the model's own copy: the accuracy knob
 * builds dozens of models a choice, each from its scene with other mode counts, and a scene
 * (150 kB, most of it input tables) copied on the stack for each would cost more than the model. */
#ifndef FLEX3RPR_MODEL_EDIT_H
#define FLEX3RPR_MODEL_EDIT_H

#include "flex3rpr/model.h"

/* f3r_model_create of `source` after edit(copy, arg) (edit may be NULL), with the edit applied
 * to the model's own copy of the scene before it is validated. */
f3r_status f3r_model_create_edited(const f3r_scene* source, void (*edit)(f3r_scene*, const void*),
                                   const void* arg, f3r_model** model, f3r_error* err);

#endif
