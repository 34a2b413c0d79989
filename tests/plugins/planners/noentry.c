/* A shared library that is not a planner: it exports a function, but not vp_planner_entry. */
#include "plugins/planner_api.h"

VP_PLANNER_EXPORT_SYMBOL int vp_planner_entry_misspelt(void) { return 1; }
