// One validation point per settings type, in the core's own words (field names such as
// `restitution`, never CLI flags or scene key paths): the scene reader prefixes the file and key
// path, World calls them on construction and addManipulator, and the Python module turns the
// InputError into ValueError. Each throws InputError("field: what is wrong (got value)").
#pragma once

#include "gradel/contacts.h"
#include "gradel/integrator.h"
#include "gradel/material.h"

namespace gradel {

constexpr int kMaxThreads = 1024;  ///< Upper bound of SimulationSettings::threads.

void validate(const SimulationSettings& s);
void validate(const ManipulatorSettings& s);
void validate(const DomainSettings& s, int dim);
void validate(const MaterialSettings& s);

}  // namespace gradel
