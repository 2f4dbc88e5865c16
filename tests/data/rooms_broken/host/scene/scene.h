#pragma once
#include "core/vec.h"
