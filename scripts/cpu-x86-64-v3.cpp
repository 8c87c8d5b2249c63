// CMakeLists.txt's PIEZO_MARCH=auto: exit 0 when the CPU running it (the
// building one) has the x86-64-v3 instruction set (AVX2, FMA, BMI2, ...).
int main() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("x86-64-v3") ? 0 : 1;
}
