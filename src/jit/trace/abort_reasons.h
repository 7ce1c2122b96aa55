// Why a tracer gives up, in one list: each entry names a construct the tracers do not compile
// and the text that --jit-stats shows for it ("interpreted: <text> (line N)"). A "{}" in a
// text stands for a detail the give-up site supplies (a variable's or function's name, a
// count), filled in order.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "frontend/source.h"

// X(Name, "text")
#define SIMIT_TRACE_ABORTS(X)                                                                      \
  /* The map and apply tracer: the site and its arguments. */                                      \
  X(FieldNotBound, "field '{}' is not bound")                                                      \
  X(FieldComponentType, "fields of this component type are not compiled")                          \
  X(GenericMappedFunction, "generic mapped functions are not compiled")                            \
  X(GridMap, "maps through grids are not compiled")                                                \
  X(InoutPartialArgument, "inout partial arguments are not compiled")                              \
  X(GlobalArgumentNotFloatVector, "a global argument other than a float vector")                   \
  X(UnexpectedParameters, "a mapped function with unexpected parameters")                          \
  X(ErrorWithInoutFields, "error statements in an apply with inout fields are not compiled")       \
  X(TraceTooLarge, "the trace is too large to compile")                                            \
  /* Values and their shapes. */                                                                   \
  X(ScalarKindValues, "{} values are not compiled")                                                \
  X(ValueType, "a value of type {} is not compiled")                                               \
  X(TensorOverSet, "a tensor over a set is not compiled here")                                     \
  X(BlockedValue, "a blocked value of type {} here")                                               \
  X(NestedBlocks, "tensors blocked on more than one level are not compiled")                       \
  X(TensorTooLarge, "a dense tensor of {} components (more than {}) is not compiled")              \
  X(ReshapeComponents, "a value of {} components bound to a variable of {}")                       \
  X(BlockedConstant, "blocked constants are not compiled")                                         \
  X(ConstantComponentType, "constants of this component type are not compiled")                    \
  X(ConstantKind, "a constant of this kind is not compiled")                                       \
  X(IndexOutOfRange, "index out of range")                                                         \
  /* Expressions. */                                                                               \
  X(IndexNotConstant, "an index that is not a constant")                                           \
  X(ComplexLiteral, "complex literals are not compiled")                                           \
  X(UnaryOfNonTensor, "unary operator on a non-tensor")                                            \
  X(NotOfNonBoolean, "not of a non-boolean")                                                       \
  X(NegationOfBoolean, "negation of a boolean")                                                    \
  X(TransposeOfNonTensor, "transpose of a non-tensor")                                             \
  X(TransposeOfHighOrder, "transpose of a tensor of order 3 or more")                              \
  X(TransposeOfOddBlocks, "transpose of a matrix whose blocks are not matrices")                   \
  X(ExpressionKind, "{} expressions are not compiled")                                             \
  X(GlobalWithoutValue, "global '{}' has no value")                                                \
  X(ReadBeforeSet, "'{}' is read before it is set")                                                \
  X(ResultRead, "reading a result of the mapped function")                                         \
  X(SetFieldRead, "reading a whole set field")                                                     \
  X(FieldOfNonMember, "a field of something other than a member")                                  \
  X(TupleNotEndpoints, "a tuple other than the endpoints")                                         \
  X(EndpointOutOfRange, "endpoint index out of range")                                             \
  X(IndexNotation, "index notation is not compiled")                                               \
  X(VectorReadNotAtMember, "a global vector read that is not at a member")                         \
  X(ReadFromValue, "reading from this value is not compiled")                                      \
  X(IndexCount, "index count does not match")                                                      \
  X(BlockedSlice, "slices of blocked tensors are not compiled")                                    \
  X(MatrixReadNotBlock, "a global matrix read that is not one block")                              \
  X(MatrixReadNotAtMembers, "a global matrix read that is not at members of the element")          \
  X(MatrixBlockShape, "a matrix block of another shape")                                           \
  X(OperandTypesDiffer, "operands of different component types")                                   \
  X(ElementwiseShapes, "element-wise operation on different shapes")                               \
  X(SystemTensorOperator, "operators on system tensors are not compiled inside a mapped function") \
  X(DivisionOfNonNumbers, "division of non-numbers")                                               \
  X(LogicOnNonBooleans, "logic on non-booleans")                                                   \
  X(Operator, "operator {} is not compiled")                                                       \
  X(CompareNonScalars, "comparison of non-scalars")                                                \
  X(CompareTypesDiffer, "comparison of different types")                                           \
  X(OrderingOfBooleans, "ordering of booleans")                                                    \
  /* Products. */                                                                                  \
  X(ProductOfNonFloats, "products of non-float tensors are not compiled")                          \
  X(InnerProductLengths, "inner product of different lengths")                                     \
  X(ProductOrientation, "product of two vectors of the same orientation")                          \
  X(ProductDimensions, "{} dimensions do not match")                                               \
  X(ProductOfHighOrder, "products of tensors of order 3 or more are not compiled")                 \
  X(ProductTooLarge, "a product of {} components (more than {}) is not compiled")                  \
  X(ProductBlockedDifferently, "a product of tensors blocked differently is not compiled")         \
  X(InnerProductBlocks, "inner product of vectors blocked differently")                            \
  /* Intrinsics and calls. */                                                                      \
  X(IntrinsicOfNonTensor, "an intrinsic of a non-tensor")                                          \
  X(IntrinsicOfBlocked, "intrinsic {} of a blocked tensor is not compiled")                        \
  X(MathOfNonFloat, "a math function of a non-float")                                              \
  X(IntrinsicOperands, "{} of these operands")                                                     \
  X(DetOrInvShape, "det or inv of this shape is not compiled")                                     \
  X(ModOfNonIntegers, "mod of non-integers")                                                       \
  X(Intrinsic, "intrinsic {} is not compiled")                                                     \
  X(SeveralResultsNotDecomposition, "a call with several results that is not a decomposition")     \
  X(DecompositionArguments, "a decomposition of several arguments")                                \
  X(DecompositionValue, "a decomposition of this value is not compiled")                           \
  X(DecompositionBlocked, "a decomposition of this blocked matrix is not compiled")                \
  X(DecompositionNotSquare, "a decomposition of a matrix that is not square")                      \
  X(ExternOrGenericCall, "calls of extern or generic functions are not compiled")                  \
  X(InlineTooDeep, "calls nested too deeply to inline")                                            \
  X(InoutTensorArgument, "inout tensor arguments are not compiled")                                \
  /* Statements. */                                                                                \
  X(MultipleAssignmentNotCall, "a multiple assignment from something other than a call")           \
  X(ResultCount, "result count does not match")                                                    \
  X(ExpressionStatement, "expression statements other than calls are not compiled")                \
  X(StatementKind, "{} statements are not compiled")                                               \
  X(LoopBoundsNotConstant, "a loop whose bounds are not constants")                                \
  X(ConditionNotBoolean, "a condition that is not a boolean")                                      \
  /* Writes. */                                                                                    \
  X(ShapeChange, "an assignment that changes a variable's shape")                                  \
  X(UnexpectedBranchAssignment,                                                                    \
    "an assignment inside a branch to '{}' that the tracer did not expect")                        \
  X(WholeResultAssignment, "assigning a whole result of the mapped function")                      \
  X(AssignmentTarget, "this assignment target is not compiled")                                    \
  X(SliceAssignment, "slice assignments are not compiled")                                         \
  X(ComponentWriteNonTensor, "a component write into a non-tensor")                                \
  X(ComponentWriteComponent, "a component write into a component")                                 \
  X(ComponentWriteType, "a component write of another type")                                       \
  X(BlockWriteShape, "a write of a block of another shape")                                        \
  X(SetFieldWrite, "writing a whole set field")                                                    \
  X(FieldWriteOtherElement, "a field write to another element")                                    \
  X(FieldWriteType, "a field write of another type")                                               \
  X(FieldWriteShape, "a field write of another shape")                                             \
  X(ResultWriteOutside, "a result write outside the mapped function")                              \
  X(ResultWriteNonFloat, "a result write of a non-float")                                          \
  X(ResultWriteBlocked, "a result write of a blocked value")                                       \
  X(ResultBlockSlice, "slices of result blocks are not compiled")                                  \
  X(ResultWriteSlice, "a result write at a slice")                                                 \
  X(ResultWriteNotAtMember, "a result write not at a member of the element")                       \
  X(MatrixWriteOneIndex, "a matrix write with one index")                                          \
  X(MatrixWriteOutsidePattern, "a matrix write outside the element's pattern")                     \
  X(VectorWriteTwoIndices, "a vector write with two indices")                                      \
  X(ResultWriteShape, "a result write of another shape")                                           \
  X(MatrixArgumentNotFloat, "a global matrix argument of non-float components")                    \
  X(MatrixArgumentRepeatsBlocks, "a global matrix argument whose pattern repeats blocks")          \
  /* The system tracer: runs of statements and their variables. */                                 \
  X(SecondWhileLoop, "a second while loop in one run of statements")                               \
  X(FieldWriteBeforeError, "a field write in a run that may stop at an error statement")           \
  X(VectorLoopCondition, "a loop condition over vectors")                                          \
  X(VectorWithoutShape, "vector '{}' has no value and no vector gives its shape")                  \
  X(StatementKindInLoop, "{} statements in a compiled loop")                                       \
  X(VariableWithoutType, "'{}' has no type")                                                       \
  X(ScalarType, "a scalar of this type")                                                           \
  X(VectorTypeNotFloat, "a vector of non-floats")                                                  \
  X(VectorNotFloat, "vector '{}' does not hold floats")                                            \
  X(MatrixWithoutValue, "matrix '{}' has no float value before the loop")                          \
  X(NonSquareBlocks, "a matrix of non-square blocks")                                              \
  X(VariableTypeInLoop, "'{}' of type {} in a compiled loop")                                      \
  X(FieldOfSetExpression, "a field of a set expression")                                           \
  X(SetNotBound, "set '{}' is not bound")                                                          \
  X(FieldNotFloat, "field '{}' does not hold floats")                                              \
  /* Expressions over scalars and vectors. */                                                      \
  X(VectorLength, "the length of this vector expression")                                          \
  X(VectorBlocks, "the blocks of this vector expression")                                          \
  X(DotLengths, "a dot product of vectors of different lengths")                                   \
  X(DotBlocks, "a dot product of vectors blocked differently")                                     \
  X(NotScalar, "a non-scalar where a scalar was expected")                                         \
  X(VariableNotScalar, "'{}' is not a scalar")                                                     \
  X(InLoop, "this {} in a compiled loop")                                                          \
  X(ExpressionKindInLoop, "{} expressions in a compiled loop")                                     \
  X(UnknownVector, "an unknown vector")                                                            \
  X(VectorProductInVector, "a product of two vectors inside a vector expression")                  \
  X(VectorPlusScalar, "a vector plus a scalar")                                                    \
  X(VectorLengths, "vectors of different lengths")                                                 \
  X(VectorOfNonFloats, "a vector operation on non-floats")                                         \
  X(VectorExpressionKind, "{} vector expressions in a compiled loop")                              \
  /* Statements over scalars and vectors. */                                                       \
  X(VectorOpInScalarIf, "a vector operation inside an if in a compiled loop")                      \
  X(AssignmentType, "an assignment of another type")                                               \
  X(AssignmentTo, "an assignment to '{}'")                                                         \
  X(VectorFirstAssignedInIf, "a vector first assigned inside an if")                               \
  X(AssignmentLength, "an assignment of another length")                                           \
  X(MatrixTimesNonVector, "a matrix times something other than a vector")                          \
  X(ProductLengths, "a product whose lengths do not match")                                        \
  X(ProductBlocks, "vector blocks differ from the matrix's")                                       \
  X(MatrixExpressionProduct, "a product of a matrix expression")                                   \
  X(DeclarationWithoutValue, "a declaration without a value")                                      \
  X(PartAssignment, "an assignment to part of a variable")                                         \
  X(VectorOpsInNestedIf, "vector operations inside an if in an if")                                \
  /* Zero folding stops (jit/zero_fold.h): the site is traced again without it. */                 \
  X(FoldDivisionByLoose, "a division by a value whose zero sign folding may change")               \
  X(FoldLooseAtan2OrPow, "atan2 or pow of a value whose zero sign may change")                     \
  X(FoldLooseOperand, "{} of a value whose zero sign folding may change")                          \
  X(FoldTiledDivision, "a division by a tiled tensor that may hold a folded zero")

namespace simit::jit {

enum class AbortReason : uint16_t {
#define SIMIT_TRACE_ABORT_ENUM(name, text) name,
  SIMIT_TRACE_ABORTS(SIMIT_TRACE_ABORT_ENUM)
#undef SIMIT_TRACE_ABORT_ENUM
};

// The entry's text, with its "{}" placeholders unfilled.
const char* abort_text(AbortReason r);
// The entry's text with its placeholders filled by `a` and `b`, in order.
std::string abort_message(AbortReason r, std::string_view a = {}, std::string_view b = {});

namespace trace_detail {

// The tracers give up: the site or run stays interpreted, with this reason and the line where
// it arose (jit/ir_build.h's GiveUp). Inside the tracers this hides give_up of a free text.
[[noreturn]] void give_up(const frontend::SourceSpan& at, AbortReason r, std::string_view a = {},
                          std::string_view b = {});

}  // namespace trace_detail

}  // namespace simit::jit
