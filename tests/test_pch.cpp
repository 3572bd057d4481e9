// The source of visvol_test_pch: empty; the target exists to build the
// precompiled header that every test reuses (see visvol_add_test).
