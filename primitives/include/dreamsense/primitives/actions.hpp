#pragma once
// F20 identifyTrajectory, answered from the child's body action (keys::kChildAction, written by
// the actions analyser from the skeleton history over its sliding window).

#include "dreamsense/perception/actions.hpp"
#include "dreamsense/primitives/context.hpp"

#include <optional>

namespace dreamsense::primitives {

// ok with {label, id, scores} once the analyser's window is full: label "none" (id 0) when no
// gesture matches (open-set rejection); no_data while the child is not in view or the window is
// not full yet. The query's window is the analyser's own (option actions.window_s): a query asking
// for another window is answered with the analyser's, and the record's query says which.
Answer<ClassLabelValue> identify_trajectory(const PrimitiveContext& ctx,
                                            const std::optional<WindowQuery>& query = std::nullopt);

}  // namespace dreamsense::primitives
