// Enki's IR sensor bug in Debian's libenki2 1:1.6.99, corrected in the Playground's process.
//
// IRSensor::init() should clear each ray's value at the start of a step; since enki commit 5d36c42
// (2018) it calls std::fill(rayValues.end(), rayValues.end(), 0), which clears nothing, so a ray
// that misses keeps what it saw last and finalize() adds it in: a wall that moves with the robot.
// Upstream fixed it in 7dbaa0b (2021, enki-community/enki#68), after Debian's package was built.
// Preloaded into asebaplayground (LD_PRELOAD), this init runs Enki's and then clears the values.
#define protected public
#include <enki/interactions/IRSensor.h>
#undef protected
#include <dlfcn.h>

#include <algorithm>

namespace Enki {
void IRSensor::init(double dt, World* w) {
    typedef void (*Init)(IRSensor*, double, World*);
    static Init enki = reinterpret_cast<Init>(dlsym(RTLD_NEXT, "_ZN4Enki8IRSensor4initEdPNS_5WorldE"));
    enki(this, dt, w);
    std::fill(rayValues.begin(), rayValues.end(), 0.0);
}
}  // namespace Enki
