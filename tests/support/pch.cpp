// The translation unit that builds the tests' precompiled header (support/pch.h); it has no code of its own.
