#pragma once
#include "scene/scene.h"  // core may not include scene
