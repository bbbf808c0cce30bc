// The two-ball scene of MultiBodyScene's determinism test and of the violent-hit test of issue 26:
// a sphere tool that crosses from x = -0.3 to 0.3 m in `crossing` seconds glances a 16^3 ball and
// pushes it into a 14^3 one (the balls meet head on at 1 m/s each). Crossing in 0.1 s (6 m/s) the
// struck ball stays in shape; in 0.05 s (12 m/s) its surface is crushed (issue 26).
#pragma once

#include <string>

namespace gradel::test {

inline std::string struckBallsScene(double crossing) {
  return R"({
    "bodies": [ { "shape": "sphere", "size": 16, "position": [-0.2, 0.1, 0], "velocity": [1, 0, 0] },
                { "shape": "sphere", "size": 14, "voxel_size": 0.012, "position": [0.1, 0.1, 0],
                  "velocity": [-1, 0, 0] } ],
    "domain": { "min": [-1, 0, -1], "max": [1, 1, 1] },
    "manipulators": [ { "type": "sphere", "radius": 0.03,
                        "path": [ { "t": 0, "position": [-0.3, 0.18, 0.08] }, { "t": )" +
         std::to_string(crossing) + R"(, "position": [0.3, 0.18, 0.08] } ] } ]
  })";
}

}  // namespace gradel::test
