#include <gtest/gtest.h>
#include "solver/rigid/rigid_world.h"
