#pragma once
// What librotacal.so exports: it is built with -fvisibility=hidden, so only what carries
// ROTACAL_API is part of its ABI (the internal code linked into it stays private to it).
#if defined(__GNUC__) || defined(__clang__)
#define ROTACAL_API __attribute__((visibility("default")))
#else
#define ROTACAL_API
#endif
